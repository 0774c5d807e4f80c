// What the binding files share: numpy arrays in (C order, converted where needed) and
// std::vector results out as numpy arrays. No math.

#ifndef EXACTFF_CORE_BIND_ARRAYS_H
#define EXACTFF_CORE_BIND_ARRAYS_H

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
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
