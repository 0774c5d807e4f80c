// The hidden region of a receiver Q seen from many points x of an emitter, for the area
// form factors (exactff/area/occluded.py, _hidden_values): each blocker (convex, in front
// of Q's plane) is clipped to the pyramid from x over a convex base in Q's plane,
// projected from x onto that plane, and the images are united as disjoint convex pieces
// (each new image less the pieces already there, by half-plane splits), then cut by the
// convex parts of Q where the base is not Q itself.
//
// Every edge of a piece carries the line it lies on, taken from the 3-D geometry and not
// from its two (rounded) ends: the trace on Q's plane of the plane through x and a
// blocker's edge, or of one of the pyramid's planes. A split is by such a line, so a
// short edge (a clipped corner, two vertices a few units of rounding apart) still cuts
// in its true direction. Only half-plane splits are used: the pieces move continuously
// with the input, the boundary of their union is within the vertices' rounding of the
// exact one, and there is no topology to get wrong. The pieces are returned as rings for
// the sector sums (kernel/sector.py).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <vector>

namespace py = pybind11;

namespace {

struct P2 {
    double x, y;
};
// 3-D work in long double (on x86 64 bits of mantissa): a crossing near x of an edge
// whose ends are far from it loses the ends' size in absolute terms, and the projection
// magnifies that near x
using real = long double;
struct P3 {
    real x, y, z;
};
// a line of Q's plane, a u + b v + c = 0, the side a u + b v + c >= 0 inside
struct Line {
    double a, b, c;
    double at(const P2& p) const { return a * p.x + b * p.y + c; }
};
// a convex polygon, counter-clockwise, and the line of each edge (v[i], v[i + 1])
struct Piece {
    std::vector<P2> v;
    std::vector<Line> l;
    void clear() {
        v.clear();
        l.clear();
    }
    size_t size() const { return v.size(); }
};
// a polygon in 3-D (offsets from x), the plane through x of each edge (inside >= 0) and a
// bound on each vertex's rounding
struct Poly3 {
    std::vector<P3> v;
    std::vector<P3> m;
    std::vector<real> e;
    void clear() {
        v.clear();
        m.clear();
        e.clear();
    }
};

inline real dot(const P3& a, const P3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline P3 cross(const P3& a, const P3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline P3 sub(const P3& a, const P3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline P3 neg(const P3& a) { return {-a.x, -a.y, -a.z}; }

double twice_area(const std::vector<P2>& p) {
    double s = 0.0;
    for (size_t i = 0, n = p.size(); i < n; ++i) {
        const P2& a = p[i];
        const P2& b = p[(i + 1) % n];
        s += (a.x - p[0].x) * (b.y - p[0].y) - (a.y - p[0].y) * (b.x - p[0].x);
    }
    return s;
}

// The part of V where dot(m, v) >= 0 (Sutherland-Hodgman; the crossing computed from the
// inside end, as exactff.halfspace.clip_halfspace); the cut edge lies on m. A crossing's
// rounding: its ends' larger one plus ulps units of the larger end's length.
void clip3(const Poly3& V, const P3& m, real ulps, Poly3& out) {
    out.clear();
    const size_t n = V.v.size();
    for (size_t i = 0; i < n; ++i) {
        const P3& a = V.v[i];
        const P3& b = V.v[(i + 1) % n];
        const real sa = dot(m, a), sb = dot(m, b);
        if (sa >= 0) {
            out.v.push_back(a);
            out.m.push_back(V.m[i]);
            out.e.push_back(V.e[i]);
        }
        if ((sa >= 0) != (sb >= 0)) {
            const P3& p = sa >= 0 ? a : b;
            const P3& q = sa >= 0 ? b : a;
            const real sp = sa >= 0 ? sa : sb, sq = sa >= 0 ? sb : sa;
            const real t = sp / (sp - sq);
            out.v.push_back({p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)});
            // leaving: the edge from the crossing runs along m; entering: along V's edge
            out.m.push_back(sa >= 0 ? m : V.m[i]);
            out.e.push_back(std::max(V.e[i], V.e[(i + 1) % n]) +
                            ulps * std::sqrt(std::max(dot(a, a), dot(b, b))));
        }
    }
}

// Split F by the line L: its part on the inside (L >= 0) and on the outside (L < 0, the
// cut edge on the reversed line), the crossings shared by both halves.
void split(const Piece& F, const Line& L, Piece& in, Piece& out) {
    in.clear();
    out.clear();
    const Line R{-L.a, -L.b, -L.c};
    const size_t n = F.size();
    for (size_t i = 0; i < n; ++i) {
        const P2& p = F.v[i];
        const P2& q = F.v[(i + 1) % n];
        const double sp = L.at(p), sq = L.at(q);
        const bool pin = sp >= 0, qin = sq >= 0;
        if (pin) {
            in.v.push_back(p);
            in.l.push_back(F.l[i]);
        } else {
            out.v.push_back(p);
            out.l.push_back(F.l[i]);
        }
        if (pin != qin) {
            // from the end inside, so that the same edge gives the same point
            const P2& u = pin ? p : q;
            const P2& w = pin ? q : p;
            const double su = pin ? sp : sq, sw = pin ? sq : sp;
            const double t = su / (su - sw);
            const P2 c{u.x + t * (w.x - u.x), u.y + t * (w.y - u.y)};
            in.v.push_back(c);
            in.l.push_back(pin ? L : F.l[i]);
            out.v.push_back(c);
            out.l.push_back(pin ? F.l[i] : R);
        }
    }
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
    bool keep(const Piece& p) {
        if (p.size() < 3) return false;
        const double a = std::fabs(twice_area(p.v));
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

// F less the convex E: F's parts outside each of E's lines in turn.
void difference(const Piece& F, const Piece& E, std::vector<Piece>& out, Piece& in,
                Piece& outside, Slivers& slivers) {
    Piece rest = F;
    for (size_t i = 0, n = E.size(); i < n && rest.size() >= 3; ++i) {
        split(rest, E.l[i], in, outside);
        if (slivers.keep(outside)) out.push_back(outside);
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

}  // namespace

// Arguments: X (n, 3) points; corners (c, 3) the pyramid's convex base in Q's plane;
// q0 (3,) a point of the plane, nQ (3,) its unit normal towards the front, RQ (2, 3)
// the plane's axes; blockers (b, k, 3) padded convex polygons with counts (b,) and unit
// normals (b, 3); edge_on a distance within which x is on a blocker's plane (seen
// edge-on, hiding nothing); vertex_ulps the rounding of an offset or a crossing in
// units of long double's roundoff of its length (of the longer end's, for a crossing); parts (p, k', 2) padded convex parts of Q in the plane's
// frame with counts (p,), none where the base is Q itself; sliver_ulps: a piece of at
// most this many units of rounding of the squared reach (twice its area) is dropped and
// counted; max_pieces: a point with more pieces is reported lost.
// Returns (xy (V, 2) ring vertices in the plane's frame, ring_start (R + 1,), ring_point
// (R,), lost (n,) bool: an image not finite, the point left empty for the caller,
// reach (n,) the largest coordinate of a point's images (before the booleans), length (n,) the pieces'
// perimeters, box (n, 4) their bounding box (the slivers' included), moved (n,) how far
// the rounding of the clipped vertices can move a point's images, and dropped (n,) the
// area of its slivers).
py::tuple hidden_pieces(py::array_t<double, py::array::c_style | py::array::forcecast> X,
                        py::array_t<double, py::array::c_style | py::array::forcecast> corners,
                        py::array_t<double, py::array::c_style | py::array::forcecast> q0,
                        py::array_t<double, py::array::c_style | py::array::forcecast> nQ,
                        py::array_t<double, py::array::c_style | py::array::forcecast> RQ,
                        py::array_t<double, py::array::c_style | py::array::forcecast> blockers,
                        py::array_t<long long, py::array::c_style | py::array::forcecast> counts,
                        py::array_t<double, py::array::c_style | py::array::forcecast> normals,
                        double edge_on, double vertex_ulps, double sliver_ulps,
                        long long max_pieces,
                        py::array_t<double, py::array::c_style | py::array::forcecast> parts,
                        py::array_t<long long, py::array::c_style | py::array::forcecast> part_counts) {
    const auto x = X.unchecked<2>();
    const auto cr = corners.unchecked<2>();
    const auto bl = blockers.unchecked<3>();
    const auto bc = counts.unchecked<1>();
    const auto bn = normals.unchecked<2>();
    const auto pa = parts.unchecked<3>();
    const auto pc = part_counts.unchecked<1>();
    const real vertex_error = vertex_ulps * std::numeric_limits<real>::epsilon();
    const P3 origin{q0.at(0), q0.at(1), q0.at(2)};
    const P3 nq{nQ.at(0), nQ.at(1), nQ.at(2)};
    const P3 ax{RQ.at(0, 0), RQ.at(0, 1), RQ.at(0, 2)};
    const P3 ay{RQ.at(1, 0), RQ.at(1, 1), RQ.at(1, 2)};
    const ssize_t n = x.shape(0), nc = cr.shape(0), nb = bl.shape(0), np_ = pa.shape(0);

    std::vector<P3> base(nc);
    for (ssize_t a = 0; a < nc; ++a) base[a] = {cr(a, 0), cr(a, 1), cr(a, 2)};
    std::vector<std::vector<P3>> K(nb);
    std::vector<P3> KN(nb);
    for (ssize_t b = 0; b < nb; ++b) {
        for (ssize_t k = 0; k < bc(b); ++k) K[b].push_back({bl(b, k, 0), bl(b, k, 1), bl(b, k, 2)});
        KN[b] = {bn(b, 0), bn(b, 1), bn(b, 2)};
    }
    // Q's convex parts, each edge's line from its two vertices (the input's own edges
    // and the diagonals between its vertices), inside towards the part's centroid
    std::vector<Piece> Qparts(np_);
    std::vector<Box> Qbox(np_);
    for (ssize_t q = 0; q < np_; ++q) {
        Piece& C = Qparts[q];
        P2 g{0.0, 0.0};
        for (ssize_t k = 0; k < pc(q); ++k) {
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
        Qbox[q] = box_of(C);
    }

    std::vector<double> xy;
    std::vector<long long> ring_start{0}, ring_point;
    std::vector<unsigned char> lost(n, 0);
    std::vector<double> reach(n, 0.0), length(n, 0.0), bounds(4 * n, 0.0), moved(n, 0.0),
        dropped(n, 0.0);
    {
        py::gil_scoped_release release;
        std::vector<P3> M(nc);
        Poly3 W, T;
        Piece img, in, outside, cut;
        std::vector<Piece> pieces, incoming, next;
        for (ssize_t i = 0; i < n; ++i) {
            const P3 p{x(i, 0), x(i, 1), x(i, 2)};
            const real h = dot(sub(p, origin), nq);
            if (!(h > 0)) continue;          // on Q's plane: Q edge-on, nothing hidden
            // the pyramid's inward planes through p
            for (ssize_t a = 0; a < nc; ++a) {
                const P3 c0 = sub(base[a], p), c1 = sub(base[(a + 1) % nc], p),
                         c2 = sub(base[(a + 2) % nc], p);
                M[a] = cross(c0, c1);
                if (dot(M[a], c2) < 0) M[a] = neg(M[a]);
            }
            const P3 foot = sub(p, origin);
            pieces.clear();
            Slivers slivers;
            bool ok = true;
            for (ssize_t b = 0; b < nb && ok; ++b) {
                // the offsets, each rounded once (within vertex_error of its length)
                W.clear();
                P3 g{0.0, 0.0, 0.0};
                for (const P3& v : K[b]) {
                    W.v.push_back(sub(v, p));
                    W.e.push_back(vertex_error * std::sqrt(dot(W.v.back(), W.v.back())));
                    g = {g.x + W.v.back().x, g.y + W.v.back().y, g.z + W.v.back().z};
                }
                if (std::fabs(dot(W.v[0], KN[b])) <= edge_on) continue;   // seen edge-on
                // wholly outside one of the pyramid's planes: clipped away, as clip3 would
                bool outside_pyramid = false;
                for (ssize_t a = 0; a < nc && !outside_pyramid; ++a) {
                    outside_pyramid = true;
                    for (const P3& v : W.v)
                        if (dot(M[a], v) >= 0) {
                            outside_pyramid = false;
                            break;
                        }
                }
                if (outside_pyramid) continue;
                // each edge's plane through p, inside towards the blocker's centroid
                for (size_t k = 0, m = W.v.size(); k < m; ++k) {
                    P3 e = cross(W.v[k], W.v[(k + 1) % m]);
                    W.m.push_back(dot(e, g) < 0 ? neg(e) : e);
                }
                for (ssize_t a = 0; a < nc && W.v.size() >= 3; ++a) {
                    bool inside = true;          // wholly inside this plane: nothing to cut
                    for (const P3& v : W.v)
                        if (dot(M[a], v) < 0) {
                            inside = false;
                            break;
                        }
                    if (inside) continue;
                    clip3(W, M[a], vertex_error, T);
                    std::swap(W, T);
                }
                if (W.v.size() < 3) continue;
                // central projection from p onto Q's plane, in the plane's frame; each
                // edge's plane m traced on it: (ax . m) u + (ay . m) v + (q0 - p) . m
                img.clear();
                for (size_t k = 0; k < W.v.size(); ++k) {
                    const P3& v = W.v[k];
                    const real down = -dot(v, nq);
                    const real s = h / down;
                    // where the vertex's rounding e takes the image: s e (1 + |v| / |v . nQ|),
                    // large for a crossing close to p
                    moved[i] = std::max(moved[i], static_cast<double>(
                        std::fabs(s) * W.e[k] * (1 + std::sqrt(dot(v, v)) / std::fabs(down))));
                    const P3 q{v.x * s + foot.x, v.y * s + foot.y, v.z * s + foot.z};
                    const P2 u{static_cast<double>(dot(q, ax)), static_cast<double>(dot(q, ay))};
                    if (!std::isfinite(u.x) || !std::isfinite(u.y)) ok = false;
                    reach[i] = std::max({reach[i], std::fabs(u.x), std::fabs(u.y)});
                    img.v.push_back(u);
                    const P3& m = W.m[k];
                    img.l.push_back({static_cast<double>(dot(ax, m)), static_cast<double>(dot(ay, m)),
                                     static_cast<double>(-dot(foot, m))});
                }
                if (!ok) break;
                slivers.min_area = sliver_ulps * DBL_EPSILON * reach[i] * reach[i];
                if (!slivers.keep(img)) continue;
                // the image less every piece already there, as disjoint convex pieces
                incoming.assign(1, img);
                const size_t have = pieces.size();
                for (size_t e = 0; e < have && !incoming.empty(); ++e) {
                    const Piece& E = pieces[e];
                    const Box be = box_of(E);
                    next.clear();
                    for (const Piece& F : incoming) {
                        if (boxes_apart(box_of(F), be) || separated_by(E, F) || separated_by(F, E))
                            next.push_back(F);
                        else
                            difference(F, E, next, in, outside, slivers);
                    }
                    incoming.swap(next);
                }
                for (Piece& F : incoming) pieces.push_back(std::move(F));
                // a point whose pieces grow past max_pieces goes to the engine instead
                if (pieces.size() > static_cast<size_t>(max_pieces)) ok = false;
            }
            if (!ok) {
                lost[i] = 1;
                continue;
            }
            // over a base other than Q, the pieces cut by Q's convex parts
            if (np_ > 0) {
                next.clear();
                for (const Piece& F : pieces) {
                    const Box bf = box_of(F);
                    for (ssize_t q = 0; q < np_; ++q)
                        if (!boxes_apart(bf, Qbox[q]) &&
                            intersect(F, Qparts[q], cut, in, outside, slivers))
                            next.push_back(cut);
                }
                pieces.swap(next);
            }
            double len = 0.0;
            Box bb = slivers.box;            // the slivers dropped lie in the region's box
            dropped[i] = slivers.dropped;
            for (const Piece& F : pieces) {
                for (size_t k = 0, m = F.size(); k < m; ++k) {
                    const P2& u = F.v[k];
                    const P2& v = F.v[(k + 1) % m];
                    xy.push_back(u.x);
                    xy.push_back(u.y);
                    len += std::hypot(v.x - u.x, v.y - u.y);
                    bb.x0 = std::min(bb.x0, u.x);
                    bb.y0 = std::min(bb.y0, u.y);
                    bb.x1 = std::max(bb.x1, u.x);
                    bb.y1 = std::max(bb.y1, u.y);
                }
                ring_start.push_back(static_cast<long long>(xy.size() / 2));
                ring_point.push_back(i);
            }
            length[i] = len;
            if (bb.x0 <= bb.x1) {
                bounds[4 * i] = bb.x0;
                bounds[4 * i + 1] = bb.y0;
                bounds[4 * i + 2] = bb.x1;
                bounds[4 * i + 3] = bb.y1;
            }
        }
    }
    const ssize_t nv = static_cast<ssize_t>(xy.size() / 2);
    py::array_t<double> out_xy({nv, static_cast<ssize_t>(2)});
    std::copy(xy.begin(), xy.end(), out_xy.mutable_data());
    py::array_t<long long> out_start(static_cast<ssize_t>(ring_start.size()));
    std::copy(ring_start.begin(), ring_start.end(), out_start.mutable_data());
    py::array_t<long long> out_point(static_cast<ssize_t>(ring_point.size()));
    std::copy(ring_point.begin(), ring_point.end(), out_point.mutable_data());
    py::array_t<bool> out_lost(n);
    std::copy(lost.begin(), lost.end(), out_lost.mutable_data());
    py::array_t<double> out_reach(n), out_length(n);
    std::copy(reach.begin(), reach.end(), out_reach.mutable_data());
    std::copy(length.begin(), length.end(), out_length.mutable_data());
    py::array_t<double> out_box({n, static_cast<ssize_t>(4)});
    std::copy(bounds.begin(), bounds.end(), out_box.mutable_data());
    py::array_t<double> out_moved(n), out_dropped(n);
    std::copy(moved.begin(), moved.end(), out_moved.mutable_data());
    std::copy(dropped.begin(), dropped.end(), out_dropped.mutable_data());
    return py::make_tuple(out_xy, out_start, out_point, out_lost, out_reach, out_length, out_box,
                          out_moved, out_dropped);
}

PYBIND11_MODULE(_hidden, m) {
    m.doc() = "The hidden region of a receiver from many points, as disjoint convex pieces "
              "(exactff.area.occluded).";
    m.def("hidden_pieces", &hidden_pieces);
}
