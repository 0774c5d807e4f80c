// The complex dilogarithm Li2(z) = -int_0^z ln(1 - t) / t dt, principal branch (cut on
// the real axis right of 1), in double precision: the closed form of the area pair's
// skew edge integrals (closed_form.cpp) takes its imaginary part on and inside the unit
// circle.
//
// The method ('t Hooft & Veltman 1979; as in A. Voigt's polylogarithm library): z is
// brought to |z| <= 1 and Re z <= 1/2 by the reflection Li2(z) = pi^2/6 - ln z ln(1 - z)
// - Li2(1 - z) (Re z > 1/2 and |1 - z| <= 1) or the inversion Li2(z) = -pi^2/6
// - ln^2(-z)/2 - Li2(1/z) (|z| > 1 or |1 - z| > 1), and there summed as the Bernoulli
// series in u = -ln(1 - z),
//     Li2(z) = u - u^2/4 + sum_k B_2k u^(2k+1) / (2k+1)!,
// where |u| <= |ln 2 + i pi/3| < 1.27 and the k-th term is below (1.27 / 2 pi)^(2k): the
// 11 terms kept leave less than 1e-22 of |u|. Re ln(1 - z) is taken as
// log1p(x (x - 2) + y^2) / 2, so that Li2(z) ~ z keeps its relative accuracy for small |z|;
// the imaginary part near the real axis keeps its own through atan2
// (tests/test_closed_compiled.py: against mpmath.polylog at 40 digits and more over the
// disk, on the circle and outside it, near 0 and within 1e-300 of the axis).

#ifndef EXACTFF_CORE_DILOG_H
#define EXACTFF_CORE_DILOG_H

#include <cmath>
#include <complex>

namespace exactff {
namespace area {

namespace dilog_detail {

// B_2k / (2k + 1)!, k = 1 .. 11 (exact fractions rounded to double)
constexpr double BERNOULLI[11] = {
    2.777777777777777777777778e-02,  -2.777777777777777777777778e-04,
    4.724111866969009826152683e-06,  -9.185773074661963995297995e-08,
    1.897886998897099999028511e-09,  -4.064761645144225526805909e-11,
    8.921691020456452555217172e-13,  -1.993929586072107568723644e-14,
    4.518980029619918191650204e-16,  -1.035651761218124701448341e-17,
    2.395218621026186745740729e-19};

constexpr double PI2_6 = 1.6449340668482264364724152;   // pi^2 / 6

struct Cx {
    double re, im;
};

inline Cx mul(Cx a, Cx b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }
inline Cx add(Cx a, Cx b) { return {a.re + b.re, a.im + b.im}; }

// ln(1 - z) = ln |1 - z| + i arg(1 - z): the modulus through log1p left of 1/2 (|1 - z|
// >= 1/2, no cancellation in x (x - 2) + y^2 there), else through hypot (1 - x exact for
// x in [1/2, 2], Sterbenz; no underflow)
inline Cx log1m(Cx z) {
    const double re = z.re < 0.5 ? 0.5 * std::log1p(z.re * (z.re - 2.0) + z.im * z.im)
                                 : std::log(std::hypot(1.0 - z.re, z.im));
    return {re, std::atan2(-z.im, 1.0 - z.re)};
}

inline Cx log_of(Cx z) { return {std::log(std::hypot(z.re, z.im)), std::atan2(z.im, z.re)}; }

// the Bernoulli series in u (|u| < 1.27): u - u^2/4 + sum_k BERNOULLI[k-1] u^(2k+1)
inline Cx series(Cx u) {
    const Cx u2 = mul(u, u);
    Cx s = {BERNOULLI[10], 0.0};
    for (int k = 9; k >= 0; --k) s = add(mul(s, u2), Cx{BERNOULLI[k], 0.0});
    // u + u^2 (-1/4 + u s)
    const Cx inner = add(Cx{-0.25, 0.0}, mul(u, s));
    return add(u, mul(u2, inner));
}

}  // namespace dilog_detail

// Li2(z), principal branch
inline std::complex<double> li2(std::complex<double> zc) {
    using namespace dilog_detail;
    const Cx z = {zc.real(), zc.imag()};
    const double nz = z.re * z.re + z.im * z.im;
    if (nz == 0.0) return zc;
    if (z.re <= 0.5 && nz <= 1.0) {
        // the series directly
        const Cx u = log1m(z);
        const Cx s = series({-u.re, -u.im});
        return {s.re, s.im};
    }
    if (z.re == 1.0 && z.im == 0.0) return {PI2_6, 0.0};
    if (z.re > 0.5 && nz <= 2.0 * z.re) {
        // reflection: |1 - z| <= 1 and Re(1 - z) < 1/2; Li2(z) = pi^2/6 - ln z ln(1 - z)
        // - Li2(1 - z), the series of 1 - z in -ln z
        const Cx lz = log_of(z);
        const Cx l1 = log1m(z);
        const Cx s = series({-lz.re, -lz.im});
        const Cx p = mul(lz, l1);
        return {PI2_6 - p.re - s.re, -p.im - s.im};
    }
    // inversion: Li2(z) = -pi^2/6 - ln^2(-z) / 2 - Li2(1/z), 1/z inside the circle with
    // Re(1/z) <= 1/2 (here |z|^2 > 2 Re z or |z| > 1 with Re z <= 1/2)
    const Cx w = {z.re / nz, -z.im / nz};
    const Cx lmz = log_of({-z.re, -z.im});
    const Cx u = log1m(w);
    const Cx s = series({-u.re, -u.im});
    const Cx l2 = mul(lmz, lmz);
    return {-PI2_6 - 0.5 * l2.re - s.re, -0.5 * l2.im - s.im};
}

}  // namespace area
}  // namespace exactff

#endif
