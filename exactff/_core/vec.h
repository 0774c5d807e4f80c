// The one 3-vector type of the compiled code, Vec3<T> (T: double, long double or the
// quadruple type), and its products. The visibility core works in Vec3<R> (R = long
// double, precision.h), the hidden regions in Vec3<double> and Vec3<long double>, the
// sector sums in the tier's type.

#ifndef EXACTFF_CORE_VEC_H
#define EXACTFF_CORE_VEC_H

#include <cmath>
#include <cstdint>

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
// geometry.py's area_vector of a polygon of k vertices vertex(0), ..., vertex(k - 1):
// half the sum of the fan's cross products about its first vertex, summed in order (the
// first product taken as it is: numpy's sum of the fan), written once for the compiled
// steps that give its values to the bit (occluded_pair.cpp, hidden_setup.cpp, curved.cpp)
template <typename T, typename Vertex>
inline Vec3<T> fan_area_vector(std::int64_t k, Vertex vertex) {
    const Vec3<T> p0 = vertex(0);
    Vec3<T> s{0, 0, 0};
    for (std::int64_t i = 1; i + 1 < k; ++i) {
        const Vec3<T> c = cross(sub(vertex(i), p0), sub(vertex(i + 1), p0));
        s = i == 1 ? c : Vec3<T>{s.x + c.x, s.y + c.y, s.z + c.z};
    }
    return {T(0.5) * s.x, T(0.5) * s.y, T(0.5) * s.z};
}
// a double vector in another precision
template <typename T>
inline Vec3<T> to(const Vec3<double>& a) { return {T(a.x), T(a.y), T(a.z)}; }

using V3 = Vec3<R>;  // the visibility core's vectors

}  // namespace exactff

#endif
