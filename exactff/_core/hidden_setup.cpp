// The set-up of an occluded pair's hidden parts (hidden_setup.h): the same steps, in the
// same order, as exactff/area/hidden.py's hidden_setup (its path where Qc is strictly
// convex and every blocker's part in front of Qc's plane is convex), with
// geometry.py's unit_normal, receiver_frame and plane_frame and halfspace.py's
// clip_front; tests/test_area_pair_compiled.py compares the two on every occluded pair
// of View3D's files.

#include "hidden_setup.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "frame.h"
#include "vec.h"

namespace exactff {
namespace {

using D3 = Vec3<double>;
double l1(const D3& a) { return std::abs(a.x) + std::abs(a.y) + std::abs(a.z); }

// geometry.unit_normal: the area vector over its length
D3 unit_normal(const std::vector<D3>& P) {
    const D3 A = fan_area_vector<double>(static_cast<std::int64_t>(P.size()),
                                         [&](std::int64_t i) { return P[i]; });
    const double L = std::sqrt(A.x * A.x + A.y * A.y + A.z * A.z);
    return {A.x / L, A.y / L, A.z / L};
}

// halfspace.clip_front of P about c: P itself (wholly in front, one vertex strictly),
// nothing (empty), or clip_halfspace's cut (the crossing from the inside end, the
// planes' meet where it agrees with it) without repeated vertices; fewer than 3: nothing
std::vector<D3> clip_front(const std::vector<D3>& P, const D3& n, const D3& c,
                           const SetupArgs& a) {
    const size_t K = P.size();
    std::vector<double> d(K);
    bool all_ge = true, any_gt = false, all_le = true;
    std::vector<D3> V(K);
    for (size_t k = 0; k < K; ++k) {
        V[k] = sub(P[k], c);
        d[k] = V[k].x * n.x + V[k].y * n.y + V[k].z * n.z;
        all_ge &= d[k] >= 0;
        any_gt |= d[k] > 0;
        all_le &= d[k] <= 0;
    }
    if (all_ge && any_gt) return P;
    if (all_le) return {};
    const double hl1 = l1(n);
    std::vector<D3> out;
    for (size_t k = 0; k < K; ++k) {
        const size_t j = (k + 1) % K;
        const bool in_k = d[k] > 0, in_j = d[j] > 0;
        if (in_k) out.push_back(V[k]);
        if (in_k == in_j) continue;
        const D3 A = in_k ? V[k] : V[j], B = in_k ? V[j] : V[k];
        const double sa = in_k ? d[k] : d[j], sb = in_k ? d[j] : d[k];
        const double t = sa / (sa - sb);
        const D3 e = sub(B, A);
        D3 X{A.x + t * e.x, A.y + t * e.y, A.z + t * e.z};
        // the meet of the edge's plane through the origin with the clipping plane,
        // ((A x e) x h) / (sa - sb), where it is the same point within the
        // interpolation's error and well conditioned
        const D3 m = cross(A, e);
        const double dd = sa - sb, la = l1(A), le = l1(e);
        const D3 mh = cross(m, n);
        const D3 meet{mh.x / dd, mh.y / dd, mh.z / dd};
        const double cond = 1.0 + hl1 * le / std::abs(dd);
        const double u = a.meet_ulps * a.eps;
        // (and on the edge's line to rounding: halfspace.clip_halfspace)
        if (l1(sub(meet, X)) <= u * (la + le) * cond &&
            l1(cross(sub(meet, A), e)) <= u * (la + le) * le && cond * u < 1.0 &&
            l1(m) > u * la * le &&
            std::abs(dd) > a.normal_floor && la * le > a.normal_floor)
            X = {meet.x + 0.0, meet.y + 0.0, meet.z + 0.0};
        out.push_back(X);
    }
    std::vector<D3> C;
    for (const D3& v : out) C.push_back({v.x + c.x, v.y + c.y, v.z + c.z});
    // a cut through a vertex repeats it: no edge of zero length
    std::vector<D3> kept;
    for (size_t k = 0; k < C.size(); ++k) {
        const D3& p = C[(k + C.size() - 1) % C.size()];
        if (C[k].x != p.x || C[k].y != p.y || C[k].z != p.z) kept.push_back(C[k]);
    }
    if (kept.size() < 3) return {};
    return kept;
}

// visibility.convex_rings of one ring: every corner's turn about n at least
// -convex_ulps eps of its cross product's scale
bool convex(const std::vector<D3>& P, const D3& n, const SetupArgs& a) {
    const size_t K = P.size();
    for (size_t k = 0; k < K; ++k) {
        const D3 e = sub(P[(k + 1) % K], P[k]), f = sub(P[(k + 2) % K], P[(k + 1) % K]);
        const double turn = dot(cross(e, f), n);
        const double scale = std::sqrt(dot(e, e) * dot(f, f));
        if (!(turn >= -a.convex_ulps * a.eps * scale)) return false;
    }
    return true;
}

}  // namespace

SetupResult hidden_setup(const SetupArgs& a) {
    SetupResult r;
    std::vector<D3> Q(static_cast<size_t>(a.n_q));
    for (std::int64_t k = 0; k < a.n_q; ++k) Q[k] = {a.Qc[3 * k], a.Qc[3 * k + 1], a.Qc[3 * k + 2]};
    // plane_frame: Qc's unit normal, origin, frame and 2-D coordinates
    const D3 nQ = unit_normal(Q), q0 = Q[0];
    const double n3[3] = {nQ.x, nQ.y, nQ.z};
    receiver_frame(n3, r.RQ);
    const D3 t1{r.RQ[0], r.RQ[1], r.RQ[2]}, t2{r.RQ[3], r.RQ[4], r.RQ[5]};
    std::vector<double> u(Q.size()), v(Q.size());
    for (size_t k = 0; k < Q.size(); ++k) {
        const D3 w = sub(Q[k], q0);
        u[k] = dot(w, t1);
        v[k] = dot(w, t2);
    }
    r.nQ[0] = nQ.x, r.nQ[1] = nQ.y, r.nQ[2] = nQ.z;
    r.q0[0] = q0.x, r.q0[1] = q0.y, r.q0[2] = q0.z;
    // the blockers' parts in front of Qc's plane
    std::vector<std::vector<D3>> Kc;
    for (std::int64_t b = 0; b < a.n; ++b) {
        std::vector<D3> P;
        for (std::int64_t k = a.start[b]; k < a.start[b + 1]; ++k)
            P.push_back({a.W[3 * k], a.W[3 * k + 1], a.W[3 * k + 2]});
        std::vector<D3> C = clip_front(P, nQ, q0, a);
        if (C.empty()) continue;
        Kc.push_back(std::move(C));
        r.kept.push_back(b);
    }
    if (Kc.empty()) {
        r.status = 1;
        return r;
    }
    // hidden.py's _strictly_convex: the base is Qc itself
    const size_t nq = Q.size();
    for (size_t k = 0; k < nq; ++k) {
        const size_t j = (k + 1) % nq, l = (k + 2) % nq;
        const double ex = u[j] - u[k], ey = v[j] - v[k], fx = u[l] - u[j], fy = v[l] - v[j];
        const double turn = ex * fy - ey * fx;
        if (!(turn > a.strict_turn * std::sqrt(ex * ex + ey * ey) * std::sqrt(fx * fx + fy * fy))) {
            r.status = 2;
            return r;
        }
    }
    // each blocker's part one convex piece, with its unit normal
    const size_t m = Kc.size();
    std::vector<D3> NK(m);
    size_t kmax = 0;
    for (size_t i = 0; i < m; ++i) {
        NK[i] = unit_normal(Kc[i]);
        if (!convex(Kc[i], NK[i], a)) {
            r.status = 2;
            return r;
        }
        kmax = std::max(kmax, Kc[i].size());
    }
    r.group.assign(m, -1);
    if (a.solid && a.inner) {
        // a solid's members outward (the inner point behind the plane); a solid with a
        // member whose plane passes within hull_rtol of the parts' size of the inner
        // point leaves as a whole
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (const auto& K : Kc)
            for (const D3& p : K) {
                lo[0] = std::min(lo[0], p.x), hi[0] = std::max(hi[0], p.x);
                lo[1] = std::min(lo[1], p.y), hi[1] = std::max(hi[1], p.y);
                lo[2] = std::min(lo[2], p.z), hi[2] = std::max(hi[2], p.z);
            }
        const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
        std::vector<long long> unsure;
        for (size_t i = 0; i < m; ++i) {
            const std::int64_t b = r.kept[i];
            const double* c = a.inner + 3 * b;
            if (std::isnan(c[0]) || std::isnan(c[1]) || std::isnan(c[2])) continue;
            r.group[i] = a.solid[b];
            if (r.group[i] < 0) continue;
            const D3 w = sub({c[0], c[1], c[2]}, Kc[i][0]);
            const double depth = w.x * NK[i].x + w.y * NK[i].y + w.z * NK[i].z;
            if (depth > 0) NK[i] = {-NK[i].x, -NK[i].y, -NK[i].z};
            if (std::abs(depth) <= a.hull_rtol * size) unsure.push_back(r.group[i]);
        }
        for (size_t i = 0; i < m; ++i)
            if (std::find(unsure.begin(), unsure.end(), r.group[i]) != unsure.end())
                r.group[i] = -1;
        // labels 0, 1, ... in increasing order of the solids
        std::map<long long, long long> label;
        for (size_t i = 0; i < m; ++i)
            if (r.group[i] >= 0) label[r.group[i]] = 0;
        long long next = 0;
        for (auto& kv : label) kv.second = next++;
        for (size_t i = 0; i < m; ++i)
            if (r.group[i] >= 0) r.group[i] = label[r.group[i]];
    }
    // padded by repeating the last vertex (rings.padded)
    r.stride = static_cast<std::int64_t>(kmax);
    r.V.resize(3 * m * kmax);
    for (size_t i = 0; i < m; ++i) {
        r.counts.push_back(static_cast<long long>(Kc[i].size()));
        for (size_t k = 0; k < kmax; ++k) {
            const D3& p = Kc[i][std::min(k, Kc[i].size() - 1)];
            double* o = &r.V[3 * (i * kmax + k)];
            o[0] = p.x, o[1] = p.y, o[2] = p.z;
        }
        r.NK.push_back(NK[i].x);
        r.NK.push_back(NK[i].y);
        r.NK.push_back(NK[i].z);
    }
    // the box of the blockers and Qc; Qc's size in its plane
    for (int k = 0; k < 3; ++k) r.lo[k] = INFINITY, r.hi[k] = -INFINITY;
    const auto grow = [&](const D3& p) {
        r.lo[0] = std::min(r.lo[0], p.x), r.hi[0] = std::max(r.hi[0], p.x);
        r.lo[1] = std::min(r.lo[1], p.y), r.hi[1] = std::max(r.hi[1], p.y);
        r.lo[2] = std::min(r.lo[2], p.z), r.hi[2] = std::max(r.hi[2], p.z);
    };
    for (const auto& K : Kc)
        for (const D3& p : K) grow(p);
    for (const D3& p : Q) grow(p);
    const auto [ul, uh] = std::minmax_element(u.begin(), u.end());
    const auto [vl, vh] = std::minmax_element(v.begin(), v.end());
    r.extent = std::max(*uh - *ul, *vh - *vl);
    return r;
}

}  // namespace exactff
