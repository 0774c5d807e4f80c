// The visibility core's hierarchical occlusion culling: the bounding box of every BSP
// subtree, and the tests that skip a subtree wholly behind the point's tangent plane or
// wholly inside the covered region (its box's conic hull filtered down the shadow tree),
// and the cube map of directions whose cells are proven covered (a fragment or a box in
// such cells is skipped).

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "constants.h"
#include "core.h"

namespace exactff {

// bounding boxes of every subtree (post-order) and the number of pieces in it
void Core::build_boxes() {
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

// is subtree k's box wholly in the closed half-space behind the point's tangent
// plane, n . (x - p) <= 0 at every corner (exactly)? Then nothing in it is in front,
// and it hides nothing in front: a part in the tangent plane has no image of area
// (the box test below cannot say so for a box that touches the plane, as every
// subtree under a floor point's own floor does)
bool Core::box_behind(const BoxCorners& b, const double* pp, const double* pn) const {
    for (int i = 0; i < 8; ++i) {
        R d = 0, mag = 0;
        for (int a = 0; a < 3; ++a) {
            const R t = b.v[i][a] * pn[a];
            d += t;
            mag += std::fabs(t);
        }
        // the filter (the differences and products within 2 roundoffs each, the
        // sum within 3 of the magnitudes), then the exact sign
        if (d < -8 * K_.eps * mag) continue;
        if (d > 8 * K_.eps * mag) return false;
        if (sign(dot_exact(pn, pp, b.c[i])) > 0) return false;
    }
    return true;
}

// is the conic hull (from p) of the box's corners wholly in covered leaves?
bool Core::box_hidden(const std::vector<Plane>& sv, int64_t k, const BoxCorners& b,
                      const V3& p, int64_t budget) const {
    // p must be outside the box (with a margin): the hull is then a pointed cone
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
        R pa = a == 0 ? p.x : (a == 1 ? p.y : p.z);
        R margin = SVBSP_BOX_MARGIN * (std::fabs(lo_[3 * k + a]) + std::fabs(hi_[3 * k + a]) +
                            std::fabs(pa)) + SVBSP_BOX_FLOOR;
        if (pa < lo_[3 * k + a] - margin || pa > hi_[3 * k + a] + margin) inside = false;
    }
    if (inside) return false;
    Vertex c[8];
    for (int i = 0; i < 8; ++i) {
        c[i] = {V3{b.v[i][0], b.v[i][1], b.v[i][2]}, b.length[i], 4 * K_.eps, -1, -1, -1, -1};
        set_double(c[i]);
    }
    thread_local std::vector<int> stack;  // (kept per thread: no allocation per box)
    stack.assign(1, 0);
    int64_t visits = 0;
    while (!stack.empty()) {
        int node = stack.back();
        stack.pop_back();
        if (node == IN) continue;
        if (is_free(node) || ++visits > budget) return false;
        const Plane& P = sv[node];
        bool pos = false, neg = false;
        const double width = static_cast<double>(K_.band + P.err);
        for (int i = 0; i < 8 && !(pos && neg); ++i) {
            // a corner clearly beyond Core::side's band by the double filter is on that
            // side; else its side in long double, 0 where unsure (both sides then); once
            // the corners are on both sides, the rest change nothing
            if (const int s = filtered_side(P, c[i], width)) {
                pos |= s > 0;
                neg |= s < 0;
                continue;
            }
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

// The cube map of directions about p: six faces (axis a, sign s), each cut into
// SVBSP_COVER_GRID x SVBSP_COVER_GRID cells of its gnomonic coordinates
// (u, w) = (v_b, v_c) / (s v_a) in [-1, 1]^2. A cell is marked covered once its cone is proven to lie in covered
// leaves of the shadow tree (Core::cell_covered); covered leaves stay covered for the
// rest of the row (a shadow only adds to them, Core::attach only merges them), so a
// fragment or a subtree's box whose cone lies in marked cells is hidden: it is skipped
// without being cut along every shadow over it. The inner grid lines are moved off the
// even values by SVBSP_COVER_OFFSET, so that they do not run along the planes of an
// axis-aligned scene seen from an axis-aligned normal (the horizon, the tiles at 0 and
// 45 degrees): a corner on such a plane cannot be decided clearly.

// the gnomonic coordinate of grid line k (0: -1, SVBSP_COVER_GRID: 1)
static double cover_line(int k) {
    if (k <= 0) return -1;
    if (k >= SVBSP_COVER_GRID) return 1;
    return -1 + 2.0 * k / SVBSP_COVER_GRID + SVBSP_COVER_OFFSET;
}

// the cell a gnomonic coordinate in [-1, 1] lies in
static int cover_cell(double u) {
    int k = static_cast<int>(std::floor((u - SVBSP_COVER_OFFSET + 1) * (SVBSP_COVER_GRID / 2.0)));
    k = std::max(0, std::min(SVBSP_COVER_GRID - 1, k));
    while (k > 0 && u < cover_line(k)) --k;  // the quotient's rounding, either way
    while (k < SVBSP_COVER_GRID - 1 && u >= cover_line(k + 1)) ++k;
    return k;
}

// the cells of one face that hold the conic hull of directions dirs[0..n) (each within
// margin[k] radians of its true direction): a convex cone whose directions all lie in
// front of a face's plane projects into the hull of its directions' projections there
// (the gnomonic projection maps a positive combination of them to a convex combination
// of their images). False where they do not fit one face
bool Core::footprint(const double (*dirs)[3], const double* margin, size_t n, Footprint* out) {
    if (n == 0) return false;
    int a = 0;
    for (int k = 1; k < 3; ++k)
        if (std::fabs(dirs[0][k]) > std::fabs(dirs[0][a])) a = k;
    const double s = dirs[0][a] > 0 ? 1.0 : -1.0;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    double umin = INFINITY, umax = -INFINITY, wmin = INFINITY, wmax = -INFINITY;
    for (size_t k = 0; k < n; ++k) {
        const double x = s * dirs[k][a];
        if (!(x > 0)) return false;
        const double u = dirs[k][b] / x, w = dirs[k][c] / x;
        // an angle d moves (u, w) by at most d (1 + u^2 + w^2) (the projection's largest
        // stretch), the quotients by 2 roundoffs
        const double m = 1.01 * margin[k] * (1 + u * u + w * w) +
                         4 * DBL_EPSILON * (1 + std::fabs(u) + std::fabs(w));
        if (!(m < 1e-3)) return false;
        umin = std::min(umin, u - m);
        umax = std::max(umax, u + m);
        wmin = std::min(wmin, w - m);
        wmax = std::max(wmax, w + m);
    }
    if (!(umin >= -1 && umax <= 1 && wmin >= -1 && wmax <= 1)) return false;
    *out = {2 * a + (s > 0 ? 0 : 1), cover_cell(umin), cover_cell(umax), cover_cell(wmin),
            cover_cell(wmax)};
    return true;
}

// fragment f's directions from p (long double differences rounded to double) with
// their errors: the rounding, and the input's own (a BSP crossing's, Vertex::gerr)
bool Core::fragment_footprint(int64_t f, const double* pp, Footprint* out) const {
    thread_local std::vector<std::array<double, 3>> dirs;
    thread_local std::vector<double> margin;
    const size_t m = static_cast<size_t>(count_[f]);
    dirs.resize(m);
    margin.resize(m);
    for (size_t k = 0; k < m; ++k) {
        const int64_t i = start_[f] + static_cast<int64_t>(k);
        R big = 0;
        R v[3];
        for (int a = 0; a < 3; ++a) {
            v[a] = static_cast<R>(V_[3 * i + a]) - pp[a];
            dirs[k][a] = static_cast<double>(v[a]);
            big = std::max(big, std::fabs(static_cast<R>(V_[3 * i + a])) + std::fabs(pp[a]));
        }
        const R length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(length > 0)) return false;
        margin[k] = static_cast<double>(4 * K_.eps * big / length + input_error(i, length)) +
                    2 * DBL_EPSILON;
    }
    return footprint(reinterpret_cast<const double(*)[3]>(dirs.data()), margin.data(), m, out);
}

// the corners of subtree k's box and their directions from p (the long double
// differences, exact where they fit) with their lengths: what the box's three tests
// (Core::box_footprint, Core::box_behind, Core::box_hidden) each take, formed once
void Core::box_corners(int64_t k, const double* pp, BoxCorners* out) const {
    for (int i = 0; i < 8; ++i) {
        double* c = out->c[i];
        c[0] = i & 1 ? hi_[3 * k] : lo_[3 * k];
        c[1] = i & 2 ? hi_[3 * k + 1] : lo_[3 * k + 1];
        c[2] = i & 4 ? hi_[3 * k + 2] : lo_[3 * k + 2];
        R* v = out->v[i];
        for (int a = 0; a < 3; ++a) v[a] = static_cast<R>(c[a]) - pp[a];
        out->length[i] = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    }
}

// the directions of subtree k's box corners from p (Core::box_hidden's cone)
bool Core::box_footprint(const BoxCorners& b, const double* pp, Footprint* out) const {
    double dirs[8][3], margin[8];
    for (int i = 0; i < 8; ++i) {
        R big = 0;
        for (int a = 0; a < 3; ++a) {
            dirs[i][a] = static_cast<double>(b.v[i][a]);
            big = std::max(big, std::fabs(static_cast<R>(b.c[i][a])) + std::fabs(pp[a]));
        }
        const R length = b.length[i];
        if (!(length > 0)) return false;
        margin[i] = static_cast<double>(4 * K_.eps * big / length) + 2 * DBL_EPSILON;
    }
    return footprint(dirs, margin, 8, out);
}

bool Core::all_covered(const Footprint& fp, const RowStats& st) {
    if (st.cover.empty()) return false;
    const size_t base = static_cast<size_t>(fp.face) * SVBSP_COVER_GRID * SVBSP_COVER_GRID;
    for (int i = fp.i0; i <= fp.i1; ++i)
        for (int j = fp.j0; j <= fp.j1; ++j)
            if (!st.cover[base + static_cast<size_t>(i * SVBSP_COVER_GRID + j)]) return false;
    return true;
}

// is the cone of cell (i, j) of `face` wholly in covered leaves? Its quadrilateral of
// corner directions (exact doubles) is filtered down the shadow tree as Core::process
// filters a piece, but every vertex must be clearly on a side of each plane it meets
// (beyond the band, the plane's tilt and slack and its own error: the true cone is then
// on that side too) or on it by construction (a crossing made on the same exact plane,
// Core::same_plane); any other vertex within that width, a free leaf or the budget
// ends the proof unproven
bool Core::cell_covered(const std::vector<Plane>& sv, const std::vector<ExactPlane>& xp,
                        int face, int i, int j, RowStats& st) const {
    const int a = face / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    const R s = face % 2 ? -1 : 1;
    struct Item {
        Piece q;
        int node;
    };
    std::vector<Item> work(1);
    for (int k = 0; k < 4; ++k) {
        const int di = k == 1 || k == 2, dj = k >= 2;
        R d[3];
        d[a] = s;
        d[b] = cover_line(i + di);
        d[c] = cover_line(j + dj);
        const V3 v{d[0], d[1], d[2]};
        work[0].q.push_back({v, norm(v), 0, -1, -1, -1, -1});
    }
    work[0].node = 0;
    ++st.cover_proofs;
    int64_t visits = 0;
    std::vector<int> sg;
    std::vector<R> dist;
    auto fail = [&]() {
        st.cover_visits += visits;
        return false;
    };
    while (!work.empty()) {
        Item w = std::move(work.back());
        work.pop_back();
        if (w.node == IN) continue;
        if (is_free(w.node) || ++visits > SVBSP_COVER_BUDGET) return fail();
        const Plane& P = sv[static_cast<size_t>(w.node)];
        const size_t m = w.q.size();
        sg.resize(m);
        dist.resize(m);
        bool pos = false, neg = false;
        for (size_t k = 0; k < m; ++k) {
            const Vertex& u = w.q[k];
            dist[k] = dot(P.m, u.v);
            const R width = (K_.band + P.err + P.slack + u.err + 16 * K_.eps) * P.mnorm * u.length;
            if (std::fabs(dist[k]) > width) {
                sg[k] = dist[k] > 0 ? 1 : -1;
            } else if (u.on_plane >= 0 &&
                       (u.on_plane == P.exact ||
                        same_plane(xp[static_cast<size_t>(u.on_plane)],
                                   xp[static_cast<size_t>(P.exact)]))) {
                sg[k] = 0;
            } else {
                return fail();
            }
            pos |= sg[k] > 0;
            neg |= sg[k] < 0;
        }
        if (!neg || !pos) {
            // on the positive side, or the negative; all on the plane: no cone
            if (pos || neg) work.push_back({std::move(w.q), pos ? P.pos : P.neg});
            continue;
        }
        // cut along the plane (Core::crossing); a vertex on the plane goes with both parts
        Piece parts[2];
        for (size_t k = 0; k < m; ++k) {
            const size_t l = (k + 1) % m;
            if (sg[k] >= 0) parts[0].push_back(w.q[k]);
            if (sg[k] <= 0) parts[1].push_back(w.q[k]);
            if (sg[k] * sg[l] >= 0) continue;
            const Vertex& x = w.q[k];
            const Vertex& y = w.q[l];
            R t;
            Vertex cut;
            crossing(P, x, y, dist[k], dist[l], &t, cut);
            cut.on_plane = P.exact;
            parts[0].push_back(cut);
            parts[1].push_back(cut);
        }
        work.push_back({std::move(parts[0]), P.pos});
        work.push_back({std::move(parts[1]), P.neg});
    }
    st.cover_visits += visits;
    return true;
}

// after a fragment was found wholly hidden: its footprint's cells, where few, proven
// covered where they can be (a cell whose proof failed is tried again only once the
// shadow tree has grown by a quarter)
void Core::prove_cells(const Footprint& fp, const std::vector<Plane>& sv,
                       const std::vector<ExactPlane>& xp, RowStats& st) const {
    if ((fp.i1 - fp.i0 + 1) * (fp.j1 - fp.j0 + 1) > SVBSP_COVER_MAX_CELLS) return;
    if (st.cover.empty()) {
        st.cover.assign(6 * SVBSP_COVER_GRID * SVBSP_COVER_GRID, 0);
        st.cover_tried.assign(6 * SVBSP_COVER_GRID * SVBSP_COVER_GRID, -1);
    }
    const size_t base = static_cast<size_t>(fp.face) * SVBSP_COVER_GRID * SVBSP_COVER_GRID;
    const int32_t size = static_cast<int32_t>(sv.size());
    for (int i = fp.i0; i <= fp.i1; ++i)
        for (int j = fp.j0; j <= fp.j1; ++j) {
            const size_t cell = base + static_cast<size_t>(i * SVBSP_COVER_GRID + j);
            if (st.cover[cell]) continue;
            const int32_t tried = st.cover_tried[cell];
            if (tried >= 0 && size < tried + tried / 4 + 64) return;
            if (cell_covered(sv, xp, fp.face, i, j, st)) {
                st.cover[cell] = 1;
                ++st.cover_cells;
            } else {
                st.cover_tried[cell] = size;
                return;  // the fragment's other cells would not complete its footprint
            }
        }
}

}  // namespace exactff
