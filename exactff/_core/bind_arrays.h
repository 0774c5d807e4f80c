// What the binding files share: numpy arrays in (C order, converted where needed) and
// std::vector results out as numpy arrays. No math.

#ifndef EXACTFF_CORE_BIND_ARRAYS_H
#define EXACTFF_CORE_BIND_ARRAYS_H

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace exactff {
namespace bind {

namespace py = pybind11;

// an argument converted to a C-ordered array of T
template <typename T>
using Array = py::array_t<T, py::array::c_style | py::array::forcecast>;

// an argument's values, copied
template <typename T>
std::vector<T> to_vector(const Array<T>& a) {
    return std::vector<T>(a.data(), a.data() + a.size());
}

// ragged polygons' starts (n + 1 offsets into `vertices` rows), checked: each polygon
// within them and of at least 3 vertices, else std::out_of_range naming `who`
inline void check_polygon_starts(const Array<std::int64_t>& start, py::ssize_t vertices,
                                 const char* who) {
    const std::int64_t* s = start.data();
    for (py::ssize_t k = 0; k + 1 < start.size(); ++k)
        if (s[k] < 0 || s[k + 1] - s[k] < 3 || s[k + 1] > vertices)
            throw std::out_of_range(std::string(who) +
                                    ": start out of range or a polygon of < 3 vertices");
}

// a result as a numpy array: 1-D, or with `columns` columns
template <typename T>
py::array_t<T> as_array(const std::vector<T>& v, py::ssize_t columns = 0) {
    py::array_t<T> out = columns ? py::array_t<T>({py::ssize_t(v.size()) / columns, columns})
                                 : py::array_t<T>(py::ssize_t(v.size()));
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
}

}  // namespace bind
}  // namespace exactff

#endif
