// The visibility core's exact predicates on the input's doubles: the side of an input
// point of a plane through the point p and two input points (orient_exact) or with an
// input normal (dot_exact), in expansion arithmetic (expansion.h), behind a long double
// filter (filtered, surely_off) that settles most of them; and ExactPlane, a plane
// through p as the input defines it.

#ifndef EXACTFF_CORE_PREDICATES_H
#define EXACTFF_CORE_PREDICATES_H

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "constants.h"
#include "expansion.h"
#include "precision.h"
#include "vec.h"

namespace exactff {

// det(a - p, b - a, x - p): the side of x of the plane through p, a, b
inline Expansion orient_exact(const double* p, const double* a, const double* b, const double* x) {
    Expansion A[3], B[3], C[3];
    for (int i = 0; i < 3; ++i) {
        A[i] = diff(a[i], p[i]);
        B[i] = diff(b[i], a[i]);
        C[i] = diff(x[i], p[i]);
    }
    Expansion m[3];
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        mul_into(m[i], B[j], C[k], 1.0);
        mul_into(m[i], B[k], C[j], -1.0);
    }
    Expansion r;
    for (int i = 0; i < 3; ++i) mul_into(r, A[i], m[i], 1.0);
    return r;
}

// n . (x - p)
inline Expansion dot_exact(const double* n, const double* p, const double* x) {
    Expansion s;
    for (int i = 0; i < 3; ++i) s = add(s, scale(diff(x[i], p[i]), n[i]));
    return s;
}

// the filter: whether the same determinant in long double is surely not 0 (beyond
// 32 roundoffs of its permanent, which bounds the subtractions' and products' rounding)
// the same determinant in long double, and a bound on its rounding error
inline void filtered(int kind, const double* p, const double* a, const double* b, const double* x,
              R* value_out, R* error_out);

inline bool surely_off(int kind, const double* p, const double* a, const double* b,
                const double* x) {
    R value, error;
    filtered(kind, p, a, b, x, &value, &error);
    return std::fabs(value) > error;
}

inline void filtered(int kind, const double* p, const double* a, const double* b, const double* x,
              R* value_out, R* error_out) {
    const R eps = std::numeric_limits<R>::epsilon();
    R value, permanent;
    if (kind == 0) {
        R A[3], B[3], C[3];
        for (int i = 0; i < 3; ++i) {
            A[i] = static_cast<R>(a[i]) - p[i];
            B[i] = static_cast<R>(b[i]) - a[i];
            C[i] = static_cast<R>(x[i]) - p[i];
        }
        R m[3] = {B[1] * C[2] - B[2] * C[1], B[2] * C[0] - B[0] * C[2],
                  B[0] * C[1] - B[1] * C[0]};
        R M[3] = {std::fabs(B[1] * C[2]) + std::fabs(B[2] * C[1]),
                  std::fabs(B[2] * C[0]) + std::fabs(B[0] * C[2]),
                  std::fabs(B[0] * C[1]) + std::fabs(B[1] * C[0])};
        value = A[0] * m[0] + A[1] * m[1] + A[2] * m[2];
        permanent = std::fabs(A[0]) * M[0] + std::fabs(A[1]) * M[1] + std::fabs(A[2]) * M[2];
    } else {
        value = 0;
        permanent = 0;
        for (int i = 0; i < 3; ++i) {
            R d = static_cast<R>(x[i]) - p[i];
            value += a[i] * d;
            permanent += std::fabs(a[i] * d);
        }
    }
    *value_out = value;
    *error_out = EXACT_FILTER_ROUNDOFFS * eps * permanent;
}

// two input points, bit for bit
inline bool same_point(const double* x, const double* y) {
    return std::memcmp(x, y, 3 * sizeof(double)) == 0;
}

// a plane through p as the input defines it: through two input points (kind 0, with
// (a - p) x (b - a) its orientation) or with normal n (kind 1, the horizon)
struct ExactPlane {
    int kind;
    double a[3], b[3];
    V3 m;       // its computed normal, in its own orientation
    R err;      // the bound on that normal's tilt, radians
    // the plane's identity for the row's cache of exact tests: kind 0, the distinct
    // input points a and b are (their ids, see Core::uid_); kind 1, -1 - its index
    int64_t ua = -1, ub = -1;
    // kind 0: the turn the input points' own errors give the plane (Core::input_tilt),
    // held apart from err (the computation's)
    R tilt = 0;
};

}  // namespace exactff

#endif
