// The one 3-vector type of the compiled code, Vec3<T> (T: double, long double or the
// quadruple type), and its products. The visibility core works in Vec3<R> (R = long
// double, precision.h), the hidden regions in Vec3<double> and Vec3<long double>, the
// sector sums in the tier's type.

#ifndef EXACTFF_CORE_VEC_H
#define EXACTFF_CORE_VEC_H

#include <cmath>

#include "precision.h"

namespace exactff {

template <typename T>
struct Vec3 {
    T x, y, z;
    T& operator[](int i) { return i == 0 ? x : i == 1 ? y : z; }
    const T& operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
};

template <typename T>
inline T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T>
inline Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
inline T norm(const Vec3<T>& a) { return std::sqrt(dot(a, a)); }
template <typename T>
inline Vec3<T> sub(const Vec3<T>& a, const Vec3<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T>
inline Vec3<T> neg(const Vec3<T>& a) { return {-a.x, -a.y, -a.z}; }
// a double vector in another precision
template <typename T>
inline Vec3<T> to(const Vec3<double>& a) { return {T(a.x), T(a.y), T(a.z)}; }

using V3 = Vec3<R>;  // the visibility core's vectors

}  // namespace exactff

#endif
