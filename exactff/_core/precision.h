// The working precisions of the compiled core: R, long double (x87 80-bit where the
// platform has it), and Quad, quadruple precision (GCC's __float128 with libquadmath on
// x86; long double again where that is already quadruple, aarch64, or where the platform
// has no quadruple type), with the few functions of Quad the core calls and its unit
// roundoff QUAD_EPS.

#ifndef EXACTFF_CORE_PRECISION_H
#define EXACTFF_CORE_PRECISION_H

#include <cfloat>
#include <cmath>
#if defined(__SIZEOF_FLOAT128__) && !defined(__aarch64__)
#include <quadmath.h>
#endif

namespace exactff {

using R = long double;  // the working precision of the visibility core

#if defined(__SIZEOF_FLOAT128__) && !defined(__aarch64__)
using Quad = __float128;
inline Quad q_atan2(Quad y, Quad x) { return atan2q(y, x); }
inline Quad q_sqrt(Quad x) { return sqrtq(x); }
inline Quad q_sin(Quad x) { return sinq(x); }
inline Quad q_abs(Quad x) { return fabsq(x); }
inline const Quad QUAD_EPS = static_cast<Quad>(std::ldexp(1.0L, -113));  // unit roundoff
#else
using Quad = long double;
inline Quad q_atan2(Quad y, Quad x) { return std::atan2(y, x); }
inline Quad q_sqrt(Quad x) { return std::sqrt(x); }
inline Quad q_sin(Quad x) { return std::sin(x); }
inline Quad q_abs(Quad x) { return std::fabs(x); }
constexpr Quad QUAD_EPS = LDBL_EPSILON / 2;
#endif

}  // namespace exactff

#endif
