// numpy's roundings, for compiled code that must give the values of a numpy reference to
// the bit (occluded_pair.cpp against exactff/area/adaptive.py): the pairwise sum of
// np.sum over a contiguous array, and the products numpy hands to the BLAS (a @ b of
// float arrays; np.linalg.norm of a vector is sqrt(x @ x)), which some x86-64 OpenBLAS
// kernels compute as a chain of fused multiply-adds in order of the inner index
// (fma(a2, b2, fma(a1, b1, a0 b0))) and others without fusing: the caller says which,
// per kind of product (compiled_pair.py probes numpy once: a vector's dot, a matrix
// product, a stacked one; OpenBLAS 0.3.31's SkylakeX kernels fuse all three, its
// Haswell and Zen ones the products but not the dot, its Sandybridge ones none).
// -ffp-contract=off keeps the rest of the expressions as written. Not imitated: a
// matrix times one column (gemv, (k, 3) @ (3, 1), as predicates.coplanar_band_sides
// takes a plane's sides), which those kernels round in an order of their own (a third
// of 3,000 random rows neither chain); occluded_pair.cpp's in_plane, a decision, may
// then differ from the reference's for a vertex within an ulp of the band's edge.
// Where the BLAS rounds otherwise than the caller says, the roundings may turn a
// decision (the cells' cuts), so that values differ beyond them, within the
// estimates: every flag wrong, the closed Cornell box at 1e-6 differed by up to 4.5e-11
// (2e-10 of the value) on 8 values, gunter1 by 7e-18.

#ifndef EXACTFF_CORE_NUMPY_OPS_H
#define EXACTFF_CORE_NUMPY_OPS_H

#include <cmath>
#include <cstddef>

namespace exactff {
namespace numpy_ops {

// np.sum of n doubles p[0], p[s], ... (numpy's pairwise_sum: below 8 in order, up to 128
// in eight interleaved partial sums, above that halves of a multiple of 8)
inline double pairwise_sum(const double* p, std::ptrdiff_t n, std::ptrdiff_t s = 1) {
    if (n < 8) {
        double r = -0.0;
        for (std::ptrdiff_t i = 0; i < n; ++i) r += p[i * s];
        return r;
    }
    if (n <= 128) {
        double r[8];
        for (int j = 0; j < 8; ++j) r[j] = p[j * s];
        std::ptrdiff_t i = 8;
        for (; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; ++j) r[j] += p[(i + j) * s];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; ++i) res += p[i * s];
        return res;
    }
    std::ptrdiff_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise_sum(p, n2, s) + pairwise_sum(p + n2 * s, n - n2, s);
}

// a @ b of two 3-vectors by the BLAS (ddot; a row of a (k, 3) @ (3, m) product): with
// fused multiply-adds in order of the inner index, as x86-64 OpenBLAS, or without (fused
// false: the products rounded and summed in order)
inline double blas_dot3(const double* a, const double* b, bool fused, std::ptrdiff_t sb = 1) {
    return fused ? std::fma(a[2], b[2 * sb], std::fma(a[1], b[sb], a[0] * b[0]))
                 : (a[0] * b[0] + a[1] * b[sb]) + a[2] * b[2 * sb];
}

// an element of a (k, 2) @ (2, m) product by the BLAS
inline double blas_dot2(const double* a, const double* b, bool fused, std::ptrdiff_t sb = 1) {
    return fused ? std::fma(a[1], b[sb], a[0] * b[0]) : a[0] * b[0] + a[1] * b[sb];
}

// the sum of three in order, as numpy reduces a row of 3 ((x0 + x1) + x2)
inline double sum3(double x0, double x1, double x2) { return (x0 + x1) + x2; }

}  // namespace numpy_ops
}  // namespace exactff

#endif
