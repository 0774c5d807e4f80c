// The sector sums of an unoccluded row in one compiled pass (exactff/kernel/point.py,
// unoccluded_row; exactff/kernel/ladder.py, extended_values): for each polygon of a list,
// its vertices taken to the receiver's local frame in offset form, clipped to the upper
// half-space, and the sector form's sum with its rounding model (sector.h)
// and the offsets' rounding. The same arithmetic, in the same order, as
// kernel/sector.py's clipped_sector_sums(..., rounded_offsets=True) and _offset_rounding,
// which stay the reference (tests/test_unoccluded_compiled.py compares them); templated
// on the working type: double for the first tier, long double for the second (on x86 64
// bits of mantissa).

#ifndef EXACTFF_CORE_SECTOR_SUMS_H
#define EXACTFF_CORE_SECTOR_SUMS_H

#include <cmath>
#include <cstdint>
#include <vector>

#include "sector.h"
#include "vec.h"

namespace exactff {
namespace kernel {

template <typename R>
inline R norm3(R x, R y, R z) { return std::sqrt(x * x + y * y + z * z); }

// a vertex in offset form and what the edges on either side of it share: its offset E
// from the polygon's first vertex, its position a = A + E from the point, |a|, and
// |E| + |A| (the scale of its rounding)
template <typename R>
struct Vx {
    Vec3<R> e, a;
    R la, size;
};

// per polygon: its sum of sector terms, the sum of their magnitudes, the terms' rounding
// estimate plus the offsets' (kernel/sector.py, clipped_sector_sums and _offset_rounding)
// (the constants as kernel/sector.py has them: Python floats, rounded to double, then
// converted to R)
template <typename R>
inline void polygon_sums(const Vec3<R>& A, const std::vector<Vx<R>>& E, double eps, double ulps,
                  double c2eps_, R* sum, R* mag, R* errs) {
    const size_t K = E.size();
    const double pi_d = 3.14159265358979323846;
    const R half_pi = static_cast<R>(pi_d / 2), four_pi = static_cast<R>(4 * pi_d);
    // gamma_8 of the offsets' rounding, and the slack of the span's cosines
    const R g = static_cast<R>(ulps * eps / (1 - ulps * eps));
    const R slack = static_cast<R>(ulps * eps);
    const R c2eps = static_cast<R>(c2eps_);
    R S = 0, M = 0, Er = 0;
    bool have_first = false;
    R fx = 0, fy = 0;   // the polygon's first horizon crossing (x, y)
    for (size_t i = 0; i < K; ++i) {
        const size_t j = i + 1 == K ? 0 : i + 1;
        Vec3<R> Ea = E[i].e, Eb = E[j].e;
        // _offset_rounding: what the offsets' rounding can move this edge's term
        R moved;
        {
            const R size_a = E[i].size, size_b = E[j].size;
            const R eta = g * (size_a >= size_b ? size_a : size_b);
            const Vec3<R>& a = E[i].a;
            const Vec3<R>& b = E[j].a;
            const Vec3<R> d{b.x - a.x, b.y - a.y, b.z - a.z};
            const R la = E[i].la, lb = E[j].la, ld = norm3(d.x, d.y, d.z);
            const R cx = a.y * b.z - a.z * b.y, cy = a.z * b.x - a.x * b.z,
                    cz = a.x * b.y - a.y * b.x;
            const R h = norm3(cx, cy, cz) / ld;
            R span = std::fabs((d.x * b.x + d.y * b.y + d.z * b.z) / (ld * lb) -
                               (d.x * a.x + d.y * a.y + d.z * a.z) / (ld * la)) +
                     slack;
            if (!(span <= 2)) span = span > 2 ? R(2) : span;
            const R turn = eta <= R(0.1) * h ? R(1.01) : half_pi;
            moved = h > eta ? 2 * eta * turn * span / h : four_pi;
            if (!std::isfinite(moved)) moved = four_pi;
            if (moved > four_pi) moved = four_pi;
            const R top = a.z >= b.z ? a.z : b.z;
            if (!(top + eta >= 0 && ld > 0)) moved = 0;
        }
        const R za = A.z + Ea.z, zb = A.z + Eb.z;
        const bool above_a = za > 0, above_b = zb > 0;
        R phi_term = 0;
        if (above_a != above_b) {
            // horizon crossing of the edge, as an offset (its height is exactly 0)
            const R t = za / (za - zb);
            const Vec3<R> EX{Ea.x + t * (Eb.x - Ea.x), Ea.y + t * (Eb.y - Ea.y),
                             Ea.z + t * (Eb.z - Ea.z)};
            const R Xx = A.x + EX.x, Xy = A.y + EX.y;
            if (!have_first) {
                have_first = true;
                fx = Xx;
                fy = Xy;
            }
            // the horizon arcs' term: the signed angle from the first crossing
            const R phi = std::atan2(fx * Xy - fy * Xx, fx * Xx + fy * Xy);
            const bool enter = !above_a;
            phi_term = enter ? phi : -phi;
            if (enter) Ea = EX;
            else Eb = EX;
        }
        R term = 0, err = 0;
        if (above_a || above_b) {
            // the edge's term and its rounding (sector.h)
            const SectorTerm<R> st = sector_term(
                A.x, A.y, A.z, Ea.x, Ea.y, Ea.z, Eb.x, Eb.y, Eb.z, c2eps);
            term = st.term;
            err = st.err;
            if (std::isnan(st.rel)) err = st.rel;   // as numpy's minimum propagates NaN
        }
        term += phi_term;
        S += term;
        M += std::fabs(term);
        Er += err + moved;
    }
    *sum = S;
    *mag = M;
    *errs = Er;
}

// Pair k (of n): polygon ids[k] (vertices V[off[i]] .. V[off[i + 1]]) from point P[rows[k]]
// in frame frames[rows[k]] (rows of the frame: the local axes, geometry.receiver_frame),
// the pairs of one row or of many: its sum S[k], the sum of its terms' magnitudes M[k],
// their rounding and the offsets' Er[k], and up[k], whether any vertex is above the
// horizon (else the caller culls it). The arrays are checked by the caller.
// frame_stride: 9, a frame per point; 0, one frame for all of them.
template <typename R>
void row_sums(const double* V, const int64_t* off, const int64_t* ids, const int64_t* rows,
              int64_t n, const double* Pd, const R* frames, double eps_, double ulps_,
              double c2eps_, R* S, R* M, R* Er, bool* up, int64_t frame_stride = 9) {
    std::vector<Vx<R>> E;
    for (int64_t k = 0; k < n; ++k) {
        const int64_t i = ids[k];
        const double* pd = Pd + 3 * rows[k];
        const R* Rm = frames + frame_stride * rows[k];
        const R p[3] = {static_cast<R>(pd[0]), static_cast<R>(pd[1]), static_cast<R>(pd[2])};
        const int64_t a = off[i], b = off[i + 1];
        const double* f = V + 3 * a;
        // geometry.rotate of (first - p) and of (vertex - first), in R
        const R fx = static_cast<R>(f[0]), fy = static_cast<R>(f[1]),
                fz = static_cast<R>(f[2]);
        const R dx = fx - p[0], dy = fy - p[1], dz = fz - p[2];
        const Vec3<R> A{dx * Rm[0] + dy * Rm[1] + dz * Rm[2],
                        dx * Rm[3] + dy * Rm[4] + dz * Rm[5],
                        dx * Rm[6] + dy * Rm[7] + dz * Rm[8]};
        E.resize(static_cast<size_t>(b - a));
        const R lA = norm3(A.x, A.y, A.z);
        bool above = false;
        for (int64_t v = a; v < b; ++v) {
            const R ex = static_cast<R>(V[3 * v]) - fx,
                    ey = static_cast<R>(V[3 * v + 1]) - fy,
                    ez = static_cast<R>(V[3 * v + 2]) - fz;
            Vx<R>& u = E[static_cast<size_t>(v - a)];
            u.e = {ex * Rm[0] + ey * Rm[1] + ez * Rm[2], ex * Rm[3] + ey * Rm[4] + ez * Rm[5],
                   ex * Rm[6] + ey * Rm[7] + ez * Rm[8]};
            u.a = {A.x + u.e.x, A.y + u.e.y, A.z + u.e.z};
            u.la = norm3(u.a.x, u.a.y, u.a.z);
            u.size = norm3(u.e.x, u.e.y, u.e.z) + lA;
            above |= u.a.z > 0;
        }
        up[k] = above;   // wholly below the horizon: the caller culls it
        polygon_sums(A, E, eps_, ulps_, c2eps_, S + k, M + k, Er + k);
    }
}

}  // namespace kernel
}  // namespace exactff

#endif
