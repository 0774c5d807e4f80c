// geometry.py's receiver_frame in doubles, written once for the compiled steps that must
// give its values to the bit (hidden_setup.cpp, occluded_pair.cpp): the orthonormal frame
// (t1, t2, n) of a normal scaled to unit length, by the branch-free construction of Duff
// et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017.

#ifndef EXACTFF_CORE_FRAME_H
#define EXACTFF_CORE_FRAME_H

#include <algorithm>
#include <cmath>

namespace exactff {

// R (3, 3), rows t1, t2, n, of the normal nv (3,) (its length summed in order, as numpy
// sums a row of 3)
inline void receiver_frame(const double* nv, double* R) {
    const double L = std::sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
    const double x = nv[0] / L, y = nv[1] / L, z = nv[2] / L;
    const double sign = z >= 0 ? 1.0 : -1.0;
    const double a = -1.0 / (sign + z);
    const double b = x * y * a;
    const double r[9] = {1.0 + sign * x * x * a, sign * b, -sign * x, b, sign + y * y * a, -y,
                         x, y, z};
    std::copy(r, r + 9, R);
}

}  // namespace exactff

#endif
