// The sides of many points for every polygon as exactff.predicates.engine_sides takes
// them, in its arithmetic (the same operations in the same order: the same bits, up to
// the order BLAS sums |n| . |p| in, which can move the in-plane test's threshold by an
// ulp): the float distance d of P[r] from polygon i's plane (through its centroid c,
// unit normal n), the band |d| <= side_ulps u (max |P[r]| + vmax[i]) where its sign
// cannot decide, and in the band whether the point lies in the plane to the rounding of
// its own coordinates and the centroid's, |d| <= u (on_ulps (|n| . |p| + |n| . |c|) +
// side_ulps |c - p|). Out: side (the sign of d, 0 in the band), band, and undecided (in
// the band and not in the plane: the pairs whose side the caller decides exactly), each
// (R, N) row-major.

#ifndef EXACTFF_CORE_SIDES_H
#define EXACTFF_CORE_SIDES_H

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace exactff {
namespace kernel {

inline void engine_sides(const double* normals, const double* centroids, const double* vmax,
                         int64_t n, const double* P, int64_t rows, double eps, double on_ulps,
                         double side_ulps, int8_t* side, bool* band, bool* undecided) {
    for (int64_t r = 0; r < rows; ++r) {
        const double* p = P + 3 * r;
        const double ax = std::fabs(p[0]), ay = std::fabs(p[1]), az = std::fabs(p[2]);
        const double top = std::max(std::max(ax, ay), az);   // (finite points: the caller's)
        for (int64_t i = 0; i < n; ++i) {
            const double* nn = normals + 3 * i;
            const double* c = centroids + 3 * i;
            // (the three products summed as numpy's einsum sums them: first and last, then
            // the middle one)
            const double d =
                -((nn[0] * (c[0] - p[0]) + nn[2] * (c[2] - p[2])) + nn[1] * (c[1] - p[1]));
            const double dtol = side_ulps * eps * (top + vmax[i]);
            const int64_t k = r * n + i;
            const bool in_band = std::fabs(d) <= dtol;
            band[k] = in_band;
            side[k] = in_band ? 0 : (d > 0 ? 1 : (d < 0 ? -1 : 0));
            bool open = false;
            if (in_band) {
                const double np_ = std::fabs(nn[0]) * ax + std::fabs(nn[1]) * ay +
                                   std::fabs(nn[2]) * az;
                const double nc = (std::fabs(nn[0]) * std::fabs(c[0]) +
                                   std::fabs(nn[2]) * std::fabs(c[2])) +
                                  std::fabs(nn[1]) * std::fabs(c[1]);
                const double x = c[0] - p[0], y = c[1] - p[1], z = c[2] - p[2];
                const double dist = std::sqrt(x * x + y * y + z * z);
                open = !(std::fabs(d) <= eps * (on_ulps * (np_ + nc) + side_ulps * dist));
            }
            undecided[k] = open;
        }
    }
}

}  // namespace kernel
}  // namespace exactff

#endif
