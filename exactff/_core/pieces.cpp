// The piece loop of the visibility core: the BSP walked front to back from the point
// (with the culling tests), each fragment filtered down the shadow tree as convex
// pieces split by its planes, the visible ones integrated (integrate.cpp), charged
// (bounds.cpp) and turned into shadows (shadow_tree.cpp).

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core.h"

namespace exactff {

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
V3 Core::between(const Vertex& a, const Vertex& b, int64_t f, R* scale) const {
    if (a.id >= 0 && b.id >= 0) {
        const double* wa = &V_[3 * a.id];
        const double* wb = &V_[3 * b.id];
        V3 e{static_cast<R>(wb[0]) - wa[0], static_cast<R>(wb[1]) - wa[1],
             static_cast<R>(wb[2]) - wa[2]};
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

// where edge x -> y crosses plane P, x and y at distances dx and dy from it (of
// opposite signs): the new vertex (computed: no input id), within K.split ulps of its
// ends' interpolated distance (and its own), plus its ends' and the plane's errors
// carried over, written into c (every field: in place where it is kept, so that no
// vertex is copied); `t` receives its parameter from x. (c must not be x or y.)
void Core::crossing(const Plane& P, const Vertex& x, const Vertex& y, R dx, R dy, R* t,
                    Vertex& c) const {
    *t = dx / (dx - dy);
    const V3 v{x.v.x + *t * (y.v.x - x.v.x), x.v.y + *t * (y.v.y - x.v.y),
               x.v.z + *t * (y.v.z - x.v.z)};
    const R l = norm(v);
    const R err = P.err + P.slack +
                  K_.split * K_.eps * ((1 - *t) * x.length + *t * y.length + l) / l +
                  std::max(x.err * x.length, y.err * y.length) / l;
    c.v = v;
    c.length = l;
    c.err = err;
    c.id = c.on_edge = c.on_plane = c.edge = -1;
    c.t = 0;
    c.err_line = 0;
    c.gerr = 0;
    set_double(c);
}

bool Core::lex_less(const V3& x, const V3& y) {
    if (x.x != y.x) return x.x < y.x;
    if (x.y != y.y) return x.y < y.y;
    return x.z < y.z;
}

// arc length between two directions
R Core::arc(const Vertex& a, const Vertex& b) {
    return std::atan2(norm(cross(a.v, b.v)), dot(a.v, b.v));
}

// an upper bound on the arc between two directions, from their doubles (for the
// charges, which need a bound, not the arc): rounding a direction to double turns it
// by at most sqrt(3) u (u = 2^-53), and atan2 of the doubles' cross and dot products
// is off the doubles' arc by a few roundoffs of it plus a few u (their absolute
// rounding, relative to |a| |b|): 16 u of each covers both with room
R Core::arc_bound(const Vertex& a, const Vertex& b) {
    const double* x = a.vd;
    const double* y = b.vd;
    const double cx = x[1] * y[2] - x[2] * y[1], cy = x[2] * y[0] - x[0] * y[2],
                 cz = x[0] * y[1] - x[1] * y[0];
    const double theta = std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz),
                                    x[0] * y[0] + x[1] * y[1] + x[2] * y[2]);
    constexpr double u = DBL_EPSILON / 2;
    return static_cast<R>(theta) * (1 + 16 * u) + 16 * u;
}

// a visible piece's value (over pi: its cosine-weighted measure, or with the sphere its
// solid angle) and the bound of its computation
void Core::piece_value(const Piece& q, int64_t f, const V3& n, const RowStats& st, R* val,
                       R* bnd) const {
    if (st.sphere)
        integrate_solid(q, f, val, bnd);
    else
        integrate(q, f, n, val, bnd, st.eq3 ? &st : nullptr);
}

// what a piece is worth at most (its value and bound), computed where first asked for
R Core::piece_worth(const Piece& q, int64_t f, const V3& n, const RowStats& st,
                    PieceWorth& w) const {
    if (!w.known) {
        R val, bnd;
        piece_value(q, f, n, st, &val, &bnd);
        w.value = val + bnd;
        w.known = true;
    }
    return w.value;
}

// whether every vertex of fragment f lies clearly behind the horizon H (the shadow
// tree's root, its negative side covered): beyond the widest width Core::process would
// test a vertex with there (the band, the plane's tilt and slack, and a vertex's own
// error, at most 2 roundoffs; the distance and the length in long double from the same
// differences, within a few roundoffs of theirs). Core::process would send such a
// fragment whole to the covered side, with no near test, no slack and no charge: the
// row's values are the same without it. (What it no longer does: prove the cells of its
// footprint covered, Core::prove_cells, which only culls later hidden fragments.)
//
// Each vertex is first decided in double where that is sure (the usual case: the band
// is far below double's roundoff): its difference from p, H's rounded normal, their
// dot product and the difference's length in double are within SVBSP_FILTER_ROUNDOFFS
// double roundoffs of |m| |v| of the long double ones (as filtered_side's), so a dot
// product beyond the long double width plus those roundoffs has the long double test's
// outcome; else the long double test decides, as before.
bool Core::behind_horizon(int64_t f, const V3& p, const Plane& H) const {
    const R w = (K_.band + H.err + H.slack + 4 * K_.eps) * H.mnorm * (1 + 64 * K_.eps);
    const double pd[3] = {static_cast<double>(p.x), static_cast<double>(p.y),
                          static_cast<double>(p.z)};
    // the width relative to |m| (rounded up), plus the roundoffs
    const double width = static_cast<double>(w / H.mnorm) * (1 + 4 * DBL_EPSILON) +
                         SVBSP_FILTER_ROUNDOFFS * DBL_EPSILON;
    for (int64_t i = start_[f]; i < start_[f] + count_[f]; ++i) {
        const double vd[3] = {V_[3 * i] - pd[0], V_[3 * i + 1] - pd[1], V_[3 * i + 2] - pd[2]};
        const double dd = H.md[0] * vd[0] + H.md[1] * vd[1] + H.md[2] * vd[2];
        const double ld = std::sqrt(vd[0] * vd[0] + vd[1] * vd[1] + vd[2] * vd[2]);
        const double reach = width * (H.mnormd * ld) * (1 + 16 * DBL_EPSILON);
        if (ld > 1e-140 && ld < 1e140) {  // (no underflow nor overflow in the filter)
            if (dd < -reach) continue;    // behind in long double too
            if (dd > reach) return false;  // in front in long double too
        }
        const V3 v{V_[3 * i] - p.x, V_[3 * i + 1] - p.y, V_[3 * i + 2] - p.z};
        if (!(dot(H.m, v) < -w * norm(v))) return false;
    }
    return true;
}

void Core::run(const double* pp, const double* pn, const int8_t* node_side,
               const int8_t* source_side, bool two_sided, bool cull, int64_t budget,
               int64_t tiles, std::vector<R>& F, std::vector<R>& E, std::vector<R>& B,
               RowStats& st) const {
    const V3 p{pp[0], pp[1], pp[2]};
    V3 n{pn[0], pn[1], pn[2]};
    R nl = norm(n);
    n = {n.x / nl, n.y / nl, n.z / nl};
    // the containers a row grows are kept per thread from row to row with their
    // capacities (cleared here), so that a row does not fault in fresh pages for them
    thread_local RowScratch scratch;
    std::vector<Plane>& sv = scratch.sv;
    std::vector<ExactPlane>& xp = scratch.xp;
    Filter& work = scratch.work;  // the filter's work list, reused by every fragment
    sv.clear();
    xp.clear();
    st.point = pp;
    st.xp = &xp;
    work.pool_peak = 0;
    std::swap(st.edges, scratch.edges);
    std::swap(st.on_plane, scratch.on_plane);
    std::swap(st.on_crossing, scratch.on_crossing);
    st.edges.clear();
    st.on_plane.clear();
    st.on_crossing.clear();
    // (given back when the row is done, whichever way it leaves)
    struct GiveBack {
        RowStats& st;
        RowScratch& scratch;
        ~GiveBack() {
            std::swap(st.edges, scratch.edges);
            std::swap(st.on_plane, scratch.on_plane);
            std::swap(st.on_crossing, scratch.on_crossing);
        }
    } give_back{st, scratch};
    // the root: the horizon, covered below
    sv.push_back({n, 1, 2 * K_.eps, OUT, IN, 0, 1});
    set_double(sv.back());
    xp.push_back({1, {pn[0], pn[1], pn[2]}, {0, 0, 0}, n, 2 * K_.eps, -1, -1});
    // the tiles: the grid cut at once into blocks of fewer than SVBSP_TILES_EAGER planes
    // along each axis, and those cut further where pieces need it (Core::grow_tile)
    if (tiles >= (1 << TILE_BITS)) throw std::invalid_argument("tiles: at most 63");
    const int all = static_cast<int>(tiles);
    if (tiles > 0) {
        tile_normals(pn, tiles, st.tiles[0][0], st.tiles[0][1]);
        sv[0].pos = cut_tiles(tile_leaf({0, all, 0, all, 0}), sv, xp, st);
    }
    if (st.sphere) {  // below the horizon free too, cut into cells about -n
        sv[0].neg = OUT;
        const double below[3] = {-pn[0], -pn[1], -pn[2]};
        if (tiles > 0) {
            tile_normals(below, tiles, st.tiles[1][0], st.tiles[1][1]);
            sv[0].neg = cut_tiles(tile_leaf({0, all, 0, all, 1}), sv, xp, st);
        }
    }
    adopt(sv, 0);  // the tiles' parents (Core::attach)
    if (nodes() == 0) return;
    struct Item {
        int64_t node;
        bool emit;
    };
    std::vector<Item> stack{{0, false}};
    while (!stack.empty() && !st.covered) {
        Item it = stack.back();
        stack.pop_back();
        const int64_t k = it.node;
        const bool near_front = node_side[k] >= 0;
        if (it.emit) {
            const auto& list = near_front ? here_front_ : here_behind_;
            for (int64_t j = here_start_[k]; j < here_start_[k + 1]; ++j) {
                const int64_t f = list[j];
                // a fragment clearly behind the tangent plane is hidden by the root:
                // skipped before its footprint (Core::behind_horizon)
                if (cull && !st.sphere && behind_horizon(f, p, sv[0])) {
                    ++st.fragments_behind;
                    continue;
                }
                // a fragment in cells proven covered is hidden (Core::cell_covered)
                Footprint fp;
                const bool mapped = cull && fragment_footprint(f, pp, &fp);
                if (mapped && all_covered(fp, st)) {
                    ++st.fragments_covered;
                    continue;
                }
                const int64_t vis0 = st.visible, hid0 = st.hidden;
                process(f, pp, p, n, source_side, two_sided, sv, xp, work, F, E, B, st);
                if (mapped && st.visible == vis0 && st.hidden > hid0) prove_cells(fp, sv, xp, st);
            }
            continue;
        }
        if (cull && size_[k] >= 4) {
            ++st.box_tests;
            // (the footprint only once the cover grid exists: Core::all_covered)
            BoxCorners corners;
            box_corners(k, pp, &corners);
            Footprint fp;
            if (!st.cover.empty() && box_footprint(corners, pp, &fp) && all_covered(fp, st)) {
                ++st.subtrees_covered;
                ++st.subtrees_culled;
                st.fragments_culled += size_[k];
                continue;
            }
            if ((!st.sphere && box_behind(corners, pp, pn)) ||
                box_hidden(sv, k, corners, p, budget)) {
                ++st.subtrees_culled;
                st.fragments_culled += size_[k];
                continue;
            }
        }
        int64_t nearc = near_front ? front_[k] : back_[k];
        int64_t farc = near_front ? back_[k] : front_[k];
        // node_side 0 or +-2 (exactff.visibility.bsp.node_sides): one of the node's own
        // fragments may stand between the point and the near subtree, so they come
        // first
        const bool first = node_side[k] % 2 == 0;
        if (farc >= 0) stack.push_back({farc, false});
        if (!first) stack.push_back({k, true});
        if (nearc >= 0) stack.push_back({nearc, false});
        if (first) stack.push_back({k, true});
    }
    settle(pp, xp, F, E, st);
    for (const auto& [key, e] : st.edges.entries())
        if (e.count == 1) {
            E[e.src] += e.charge;
            st.crossing[static_cast<size_t>(e.src)] += e.geo;
        }
    // what the row held beyond its n-long results: the shadow tree and its exact
    // planes, the traversal's stack, the work list's pieces at their most, the edge
    // charges and the exact tests' cache (containers only grow during a row, so their
    // capacities are their peaks)
    st.working_bytes = static_cast<int64_t>(
        sv.size() * sizeof(Plane) + xp.size() * sizeof(ExactPlane) +
        stack.capacity() * sizeof(Item) + work.pool_peak * sizeof(Vertex) +
        static_cast<size_t>(st.held_peak) * sizeof(Corner) +
        st.edges.bytes() +
        st.on_plane.bytes() + st.on_crossing.bytes() + st.held_bytes);
    // a visible sliver whose shadow was left out may wrongly show any later piece
    // behind it: its area goes to every receiving polygon's band bound
    if (st.unattributed > 0)
        for (int64_t i = 0; i < n_sources_; ++i)
            if (source_side[i] > 0 || (two_sided && source_side[i] < 0))
                B[i] += st.unattributed;
}

void Core::process(int64_t f, const double* pp, const V3& p, const V3& n,
                   const int8_t* source_side, bool two_sided, std::vector<Plane>& sv,
                   std::vector<ExactPlane>& xp, Filter& work, std::vector<R>& F,
                   std::vector<R>& E, std::vector<R>& B, RowStats& st) const {
    const int64_t src = source_[f];
    const int s = source_side[src];
    if (s == 0) return;  // seen edge-on: no image, hides nothing
    ++st.fragments;
    const bool receives = s > 0 || two_sided;
    // the fragment's vertices, then the crossings its pieces make; a piece is a run of
    // (vertex, edge to the next) on the work list's stack of corners, so that cutting
    // a piece copies no vertex
    auto& pool = work.pool;
    std::vector<Corner>& corners = work.corners;
    std::vector<Filter::Item>& items = work.items;
    pool.clear();
    corners.clear();
    items.clear();
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
        pool.push_back({v, length, exact ? static_cast<R>(0) : 2 * K_.eps, i, -1, -1, i});
        pool.back().gerr = input_error(i, length);
        set_double(pool.back());
        corners.push_back({static_cast<int32_t>(pool.size() - 1), i});
    }
    items.push_back({0, 0, true});
    st.held = static_cast<int64_t>(corners.size());
    // the first step enters the root from a virtual link
    bool first = true;
    // each step's corners, signs, distances and crossings (reused: no allocation per step)
    std::vector<Corner>& cur = work.cur;
    std::vector<int>& sg = work.sg;
    std::vector<R>& d = work.d;
    std::vector<R>& arcs = work.arcs;
    std::vector<int32_t>& cut = work.cut;
    while (!items.empty()) {
        const Filter::Item w = items.back();
        items.pop_back();
        // the top item's corners are the stack's last: taken off it
        cur.assign(corners.begin() + static_cast<std::ptrdiff_t>(w.begin), corners.end());
        corners.resize(w.begin);
        // vertices held by the work list (with this piece): for the row's peak
        st.held_peak = std::max(st.held_peak, st.held);
        st.held -= static_cast<int64_t>(cur.size());
        // the piece goes down from the link it came by; where a node sends it whole to
        // one side, it goes on from there at once (no copy back onto the work list)
        int plane = w.plane;
        bool positive = w.positive;
      descend:
        int node;
        if (first) {
            node = 0;
            first = false;
        } else {
            node = positive ? sv[plane].pos : sv[plane].neg;
        }
        if (node <= LAZY) {  // a block of tiles: cut where the piece lies on one side
            const int cut = grow_tile(node, plane, positive, work, sv, xp, st);
            if (cut >= 0) node = cut;
        }
        if (node == IN) {
            ++st.hidden;
            continue;
        }
        if (is_free(node)) {
            ++st.visible;
            Piece& q = work.piece;
            q.resize(cur.size());
            for (size_t i = 0; i < cur.size(); ++i) {
                q[i] = pool[static_cast<size_t>(cur[i].v)];
                q[i].edge = cur[i].edge;
            }
            // its value and bound: a piece whose polygon receives nothing (seen from
            // behind, one-sided) needs them only where its shadow is left out
            // (Core::insert_shadow asks for them there, Core::piece_worth)
            R val = 0, bnd = 0;
            if (receives) piece_value(q, f, n, st, &val, &bnd);
            bool held = false;
            arcs.clear();
            if (receives && st.rtol > 0) {
                // the second tier where the sums' rounding or the vertices' errors
                // exceed the tolerance times the value: decided at the row's end for the
                // piece's polygon as a whole (Core::settle), so that slivers whose bounds
                // are negligible next to their polygon's value stay in long double
                const R charges = charge_edges(q, src, E, st, nullptr, false, nullptr, &arcs);
                held = bnd + charges > st.rtol * val;
            }
            if (receives && !held) {
                F[src] += val;
                E[src] += bnd;
                charge_edges(q, src, E, st, nullptr, true, nullptr, &arcs, f);
            }
            if (receives) B[src] += leaked(q, val + bnd, st);
            // a piece whose shadow is left out is an image folded or flat along a side
            // (seen from within the band of a plane it is not planar in): its own value
            // is charged it too, as the band's slivers are
            PieceWorth worth{receives ? val + bnd : 0, receives};
            if (!insert_shadow(q, f, pp, plane, positive, sv, xp, st, worth, n) && receives)
                B[src] += val + bnd;
            if (held) {
                ++st.pieces_held;
                st.held_pieces.push_back({q, f, val, bnd, arcs});
            }
            continue;
        }
        // (the plane as this piece meets it: its slack grows only once the piece is past)
        const Plane& P = sv[node];
        R slack = P.slack;
        const size_t m = cur.size();
        auto at = [&](size_t i) -> const Vertex& { return pool[static_cast<size_t>(cur[i].v)]; };
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
            const Vertex& u = at(i);
            // a vertex clearly beyond the widest band is decided by the double filter
            // (its long double distance is then computed only if the piece is cut)
            if (const int s = filtered_side(P, u, plane_width)) {
                sg[i] = s;
                pos |= s > 0;
                neg |= s < 0;
                d[i] = NAN;
                continue;
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
                R adjacent = arc(at(i == 0 ? m - 1 : i - 1), u) + arc(u, at(i + 1 == m ? 0 : i + 1));
                if (receives)
                    B[src] += adjacent * width / 3.14159265358979323846264338327950288L;
                // the sliver, on whichever side it truly is, also hides or uncovers
                // what lies behind it near this plane: every later piece classified
                // or cut here is charged it too (the plane's slack; not fed back into
                // the slack itself, so that it does not grow hit by hit)
                slack = std::max(slack, K_.band + P.err + u.err);
            }
        }
        if (!neg || !pos) {
            sv[node].slack = slack;  // on one side (or in the plane: either side)
            plane = node;
            positive = !neg;
            goto descend;
        }
        ++st.splits;
        for (size_t i = 0; i < m; ++i)
            if (std::isnan(d[i])) d[i] = dot(P.m, at(i).v);
        cut.assign(m, -1);
        // room for the crossings (at most one an edge) made before any is taken: each is
        // built in its place at the pool's end, its ends still read from the pool
        if (pool.size() + m > pool.capacity())
            pool.reserve(std::max(pool.size() + m, 2 * pool.capacity()));
        for (size_t i = 0; i < m; ++i) {
            const size_t j = i + 1 == m ? 0 : i + 1;
            if ((sg[i] > 0 && sg[j] < 0) || (sg[i] < 0 && sg[j] > 0)) {
                // the crossing computed from the edge's ends in a fixed order, so
                // that the piece across the edge gets the same point bit for bit
                const bool swap = lex_less(at(j).v, at(i).v);
                const Vertex& x = swap ? at(j) : at(i);
                const Vertex& y = swap ? at(i) : at(j);
                const R dx = swap ? d[j] : d[i], dy = swap ? d[i] : d[j];
                R t;
                cut[i] = static_cast<int32_t>(pool.size());
                pool.emplace_back();
                Vertex& c = pool.back();
                crossing(P, x, y, dx, dy, &t, c);
                const R l = c.length;
                // off the true plane by its tilt; off the true edge's by its ends'
                // world errors over its distance (as the computation's, above)
                c.gerr = xp[static_cast<size_t>(P.exact)].tilt +
                         std::max(x.gerr * x.length, y.gerr * y.length) / l;
                // the parameter along the input edge the piece's edge i -> j lies on
                const Vertex& xi = at(i);
                const Vertex& yj = at(j);
                const R ti = swap ? 1 - t : t;
                if (cur[i].edge >= 0) {  // on an input edge: exactly known
                    const int64_t ia = cur[i].edge;
                    const int64_t ib = ia + 1 == start_[f] + count_[f] ? start_[f] : ia + 1;
                    R tx = -1, ty = -1;  // the ends' parameters along it
                    if (xi.id == ia) tx = 0;
                    else if (xi.on_edge == ia) tx = xi.t;
                    if (yj.id == ib) ty = 1;
                    else if (yj.on_edge == ia) ty = yj.t;
                    if (tx >= 0 && ty >= 0) {
                        c.on_edge = ia;
                        c.on_plane = P.exact;
                        c.t = tx + ti * (ty - tx);
                        // off the edge's line: the interpolation's rounding, and its
                        // ends' own distances from it
                        auto off = [&](const Vertex& u) {
                            return u.id >= 0 ? u.err : u.err_line;
                        };
                        c.err_line =
                            4 * K_.eps + std::max(off(xi) * xi.length, off(yj) * yj.length) / l;
                    }
                }
            }
        }
        // the two parts, each vertex with the edge to its successor: the input edge
        // it was on, or the cut along this plane (each corner written in its place: a
        // braced temporary would be stored in halves and read back whole)
        const int64_t cut_edge = -1 - static_cast<int64_t>(P.exact);
        auto add_corner = [&](int32_t v, int64_t edge) {
            Corner& c = corners.emplace_back();
            c.v = v;
            c.edge = edge;
        };
        for (int sigma : {-1, 1}) {
            // a part whose side of the plane is a covered leaf is hidden there: counted,
            // not formed (its corners would only be taken off the work list again)
            if ((sigma > 0 ? P.pos : P.neg) == IN) {
                ++st.hidden;
                continue;
            }
            const size_t begin = corners.size();
            for (size_t i = 0; i < m; ++i) {
                const size_t j = i + 1 == m ? 0 : i + 1;
                const int si = sigma * sg[i], sj = sigma * sg[j];
                if (si >= 0) add_corner(cur[i].v, si == 0 && sj < 0 ? cut_edge : cur[i].edge);
                if ((si > 0 && sj < 0) || (si < 0 && sj > 0))
                    add_corner(cut[i], si > 0 ? cut_edge : cur[i].edge);
            }
            Filter::Item& it = items.emplace_back();
            it.begin = begin;
            it.plane = node;
            it.positive = sigma > 0;
            st.held += static_cast<int64_t>(corners.size() - begin);
        }
        sv[node].slack = slack;
    }
    work.pool_peak = std::max(work.pool_peak, pool.size());
}

}  // namespace exactff

namespace exactff {

// the pieces Core::process held (their bound above rtol times their value), per
// polygon: where the polygon's bound with all of them as integrated in long double is
// within its target, they stay so; else each is refined and integrated in quadruple
// precision (Core::refine, Core::integrate_quad), the better of the two kept, a piece
// at a time as before. The target is rtol times the larger of the polygon's value and
// half the floor (RowStats::floor: the default call's VALUE_FLOOR, which
// exactff.errors.misses_tolerance accepts on every path; the half so that the row's
// remaining roundings keep it there; 0 for a bound relative to the value however small,
// exactff.testing.ground_truth). That bound is the row's so far (E, and the edge charges
// still pending, RowStats::edges with one piece), plus the held pieces' own bounds and
// edge charges, less the charges of the edges two pieces of the polygon share (which
// Core::charge_edges cancels: exactly two pieces, one polygon, neither refined)
void Core::settle(const double* pp, const std::vector<ExactPlane>& xp, std::vector<R>& F,
                  std::vector<R>& E, RowStats& st) const {
    if (st.held_pieces.empty()) return;
    st.held_bytes = static_cast<int64_t>(st.held_pieces.capacity() * sizeof(RowStats::Held));
    for (const auto& h : st.held_pieces)
        st.held_bytes += static_cast<int64_t>(h.q.capacity() * sizeof(Vertex));
    std::vector<R> total(F.begin(), F.end()), keep(E.begin(), E.end());
    for (const auto& [key, e] : st.edges.entries())
        if (e.count == 1) keep[static_cast<size_t>(e.src)] += e.charge;
    struct Met {
        int64_t src;  // -1: pieces of two polygons
        int count;
        R charge;
    };
    KeyTable<Met> met;
    std::vector<std::pair<EdgeKey, R>> keyed;
    for (auto& h : st.held_pieces) {
        const size_t src = static_cast<size_t>(source_[h.f]);
        total[src] += h.val;
        keyed.clear();
        keep[src] += h.bnd + charge_edges(h.q, source_[h.f], E, st, nullptr, false, &keyed,
                                          &h.arcs);
        for (const auto& [k, c] : keyed) {
            Met& o = met.emplace(k, Met{source_[h.f], 0, 0});
            o.count += 1;
            o.charge += c;
            if (o.src != source_[h.f]) o.src = -1;
        }
    }
    for (const auto& [k, o] : met.entries()) {
        if (o.src < 0) continue;
        const EdgeCharge* it = st.edges.find(k);
        if (it == nullptr) {
            if (o.count == 2) keep[static_cast<size_t>(o.src)] -= o.charge;
        } else if (o.count == 1 && it->count == 1 && it->src == o.src && !it->refined) {
            keep[static_cast<size_t>(o.src)] -= o.charge + it->charge;
        }
    }
    std::vector<int64_t> count(F.size(), 0);
    for (const auto& h : st.held_pieces) ++count[static_cast<size_t>(source_[h.f])];
    // a polygon's target, from its value summed (the floor's half: see above)
    const R half_floor = st.floor / 2;
    auto target = [&](size_t s) { return st.rtol * std::max(total[s], half_floor); };
    std::vector<std::array<Quad, 3>> qdirs;
    std::vector<R> qerrs, lerrs;
    Piece r;
    const V3 n{st.normal[0], st.normal[1], st.normal[2]};
    const R nl = norm(n);
    const V3 un{n.x / nl, n.y / nl, n.z / nl};
    for (auto& h : st.held_pieces) {
        const int64_t src = source_[h.f];
        const size_t s = static_cast<size_t>(src);
        R val = h.val, bnd = h.bnd;
        const std::vector<R>* placed = nullptr;  // the vertices' bounds charged, if refined
        // (the subtractions above within a few roundoffs of the sums: 64 kept)
        if (!(keep[s] * (1 + 64 * K_.eps) <= target(s))) {
            const R charges = charge_edges(h.q, src, E, st, nullptr, false, nullptr, &h.arcs);
            refine(h.q, h.f, pp, xp, qdirs, qerrs);
            // first the refined directions rounded to long double, summed in long double
            // (Core::integrate, with offsets from the directions, each within 4 roundoffs
            // of the larger length: that much more on each vertex's bound): enough where
            // the vertices' errors, not the sum's rounding, made the bound, as on slivers
            // cut between nearly parallel planes; kept where within the piece's share of
            // its polygon's tolerance, else the sum in quadruple precision
            r = h.q;
            lerrs.resize(r.size());
            for (size_t i = 0; i < r.size(); ++i) {
                if (r[i].id < 0) {
                    r[i].v = {static_cast<R>(qdirs[i][0]), static_cast<R>(qdirs[i][1]),
                              static_cast<R>(qdirs[i][2])};
                    r[i].length = norm(r[i].v);
                    r[i].on_edge = -1;
                }
            }
            for (size_t i = 0; i < r.size(); ++i)
                lerrs[i] = qerrs[i] + 4 * K_.eps * (2 + r[0].length / r[i].length);
            R lv, lb;
            integrate(r, h.f, un, &lv, &lb, st.eq3 ? &st : nullptr);
            const R lcharges = charge_edges(h.q, src, E, st, &lerrs, false, nullptr, &h.arcs);
            if (lb + lcharges < bnd + charges &&
                lb + lcharges <= target(s) / (2 * static_cast<R>(count[s]))) {
                val = lv;
                bnd = lb;
                placed = &lerrs;
            } else {
                R qv, qb;
                integrate_quad(qdirs, st.normal, &qv, &qb, st.eq3);
                ++st.quad_pieces;
                const R qcharges = charge_edges(h.q, src, E, st, &qerrs, false, nullptr, &h.arcs);
                if (qb + qcharges < bnd + charges) {
                    val = qv;
                    bnd = qb;
                    placed = &qerrs;
                }
            }
        }
        F[src] += val;
        E[src] += bnd;
        charge_edges(h.q, src, E, st, placed, true, nullptr, &h.arcs, h.f);
    }

    st.held_pieces.clear();
}

}  // namespace exactff
