// The visibility core's hierarchical occlusion culling: the bounding box of every BSP
// subtree, and the tests that skip a subtree wholly behind the point's tangent plane or
// wholly inside the covered region (its box's conic hull filtered down the shadow tree).

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
bool Core::box_behind(int64_t k, const double* pp, const double* pn) const {
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
bool Core::box_hidden(const std::vector<Plane>& sv, int64_t k, const V3& p,
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
        R margin = SVBSP_BOX_MARGIN * (std::fabs(lo_[3 * k + a]) + std::fabs(hi_[3 * k + a]) +
                            std::fabs(pa)) + SVBSP_BOX_FLOOR;
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

}  // namespace exactff
