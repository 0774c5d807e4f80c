// The visibility core's constructor (the scene's arrays, the subtrees' boxes, one id per
// distinct input point) and a row's set-up (Eq. 3's frame) and results (each bound
// rounded up to double).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core.h"

namespace exactff {

Core::Core(std::vector<double> vertices, std::vector<int64_t> start, std::vector<int64_t> count,
           std::vector<int64_t> source, std::vector<int64_t> front, std::vector<int64_t> back,
           std::vector<int64_t> here_start, std::vector<int64_t> here_front,
           std::vector<int64_t> here_behind, int64_t n_sources, double band, double c1,
           double c2, double split, std::vector<double> vertex_errors)
    : n_sources_(n_sources), V_(std::move(vertices)), VE_(std::move(vertex_errors)),
      start_(std::move(start)), count_(std::move(count)), source_(std::move(source)),
      front_(std::move(front)), back_(std::move(back)), here_start_(std::move(here_start)),
      here_front_(std::move(here_front)), here_behind_(std::move(here_behind)) {
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

RowResult Core::row(const double* pp, const double* pn, const int8_t* ns, const int8_t* ss,
                    bool two_sided, bool cull, int64_t box_budget, int64_t tiles, double rtol,
                    double floor, bool eq3, bool sphere) const {
    RowResult out;
    RowStats& st = out.stats;
    out.F.assign(n_sources_, 0);
    out.E.assign(n_sources_, 0);
    out.B.assign(n_sources_, 0);
    out.G.assign(n_sources_, 0);
    st.crossing.assign(static_cast<size_t>(n_sources_), 0);
    // the sphere's pieces have no second tier (their measure has no quadruple form)
    st.rtol = sphere ? 0 : rtol;
    st.floor = floor;
    st.leak_budget = SVBSP_LEAK_BUDGET_SHARE * (rtol > 0 ? rtol : 1e-12);
    st.normal = pn;
    st.eq3 = eq3 && !sphere;
    st.cull = cull;
    st.sphere = sphere;
    if (st.eq3) {
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
    std::vector<R> f(n_sources_, 0), e(n_sources_, 0), b(n_sources_, 0);
    run(pp, pn, ns, ss, two_sided, cull, box_budget, tiles, f, e, b, st);
    const R half_ulp = std::numeric_limits<double>::epsilon() / 2;
    for (int64_t i = 0; i < n_sources_; ++i) {
        out.F[i] = static_cast<double>(f[i]);
        // the bound, and the rounding of the value to double
        out.E[i] = static_cast<double>(e[i] + half_ulp * std::fabs(f[i])) *
                   (1 + 4 * std::numeric_limits<double>::epsilon());
        out.B[i] = static_cast<double>(b[i]) * (1 + 4 * std::numeric_limits<double>::epsilon());
        out.G[i] = static_cast<double>(st.crossing[static_cast<size_t>(i)]) *
                   (1 + 4 * std::numeric_limits<double>::epsilon());
    }
    return out;
}


}  // namespace exactff
