// The double 3-vectors of an occluded pair's compiled path (pair.cpp, curved.cpp): a row
// of an (n, 3) array, a sum and a multiple, beside vec.h's products and differences.

#ifndef EXACTFF_CORE_PAIR_VEC_H
#define EXACTFF_CORE_PAIR_VEC_H

#include "vec.h"

namespace exactff {
namespace pair_vec {

using D3 = Vec3<double>;

inline D3 at(const double* p) { return {p[0], p[1], p[2]}; }
inline D3 add(const D3& a, const D3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline D3 scale(double s, const D3& a) { return {s * a.x, s * a.y, s * a.z}; }

}  // namespace pair_vec
}  // namespace exactff

#endif
