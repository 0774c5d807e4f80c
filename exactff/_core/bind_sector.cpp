// Python module exactff.kernel._sector: the unoccluded rows' sector sums (sector_sums.h),
// in double and in long double, and the sides of their points (sides.h). Arrays in and
// out, the GIL released around the computation; no math.

#include <cstdint>
#include <stdexcept>

#include "bind_arrays.h"
#include "sector_sums.h"
#include "sides.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;

namespace {

template <typename R>
py::tuple row_sums(Array<double> V, Array<int64_t> offsets, Array<int64_t> ids,
                   Array<int64_t> rows, Array<double> P, Array<R> frames, double eps,
                   double ulps, double c2eps) {
    const int64_t n = ids.size();
    const int64_t npoly = offsets.size() - 1;
    const int64_t nrows = P.size() / 3;
    if (V.ndim() != 2 || V.shape(1) != 3 || P.size() != 3 * nrows ||
        frames.size() != 9 * nrows || rows.size() != n)
        throw std::invalid_argument(
            "row_sums: V (N, 3), ids (K,), rows (K,), P (M, 3), frames (M, 3, 3) expected");
    const int64_t* off = offsets.data();
    const int64_t* id = ids.data();
    const int64_t* row = rows.data();
    for (int64_t k = 0; k < n; ++k) {
        if (id[k] < 0 || id[k] >= npoly || off[id[k]] >= off[id[k] + 1] ||
            off[id[k] + 1] > V.shape(0))
            throw std::out_of_range("row_sums: polygon id out of range or empty");
        if (row[k] < 0 || row[k] >= nrows) throw std::out_of_range("row_sums: row out of range");
    }
    py::array_t<R> S(n), M(n), E(n);
    py::array_t<bool> up(n);
    {
        py::gil_scoped_release release;
        exactff::kernel::row_sums(V.data(), off, id, row, n, P.data(), frames.data(), eps, ulps,
                                  c2eps, S.mutable_data(), M.mutable_data(), E.mutable_data(),
                                  up.mutable_data());
    }
    return py::make_tuple(S, M, E, up);
}

// exactff.predicates.engine_sides before its exact tests (sides.h): side, band and
// undecided, each (R, N)
py::tuple engine_sides(Array<double> normals, Array<double> centroids, Array<double> vmax,
                       Array<double> P, double eps, double on_ulps, double side_ulps) {
    const int64_t n = vmax.size();
    const int64_t rows = P.size() / 3;
    if (normals.size() != 3 * n || centroids.size() != 3 * n || P.size() != 3 * rows)
        throw std::invalid_argument(
            "engine_sides: normals (N, 3), centroids (N, 3), vmax (N,), P (R, 3) expected");
    py::array_t<int8_t> side({rows, n});
    py::array_t<bool> band({rows, n}), undecided({rows, n});
    {
        py::gil_scoped_release release;
        exactff::kernel::engine_sides(normals.data(), centroids.data(), vmax.data(), n,
                                      P.data(), rows, eps, on_ulps, side_ulps,
                                      side.mutable_data(), band.mutable_data(),
                                      undecided.mutable_data());
    }
    return py::make_tuple(side, band, undecided);
}

}  // namespace

PYBIND11_MODULE(_sector, m) {
    m.doc() = "Sector sums of unoccluded rows (exactff.kernel.point.unoccluded_rows), and the "
              "sides of their points (exactff.predicates.engine_sides)";
    m.def("row_sums", &row_sums<double>, py::arg("V"), py::arg("offsets"), py::arg("ids"),
          py::arg("rows"), py::arg("P"), py::arg("frames"), py::arg("eps"), py::arg("ulps"),
          py::arg("c2eps"),
          "row_sums(V, offsets, ids, rows, P, frames, eps, ulps, c2eps) -> (S, mags, errs, "
          "above): polygon ids[k] from P[rows[k]] in the frame frames[rows[k]], double "
          "precision");
    m.def("row_sums_extended", &row_sums<long double>, py::arg("V"), py::arg("offsets"),
          py::arg("ids"), py::arg("rows"), py::arg("P"), py::arg("frames"), py::arg("eps"),
          py::arg("ulps"), py::arg("c2eps"), "the same in long double (frames in long double)");
    m.def("engine_sides", &engine_sides, py::arg("normals"), py::arg("centroids"),
          py::arg("vmax"), py::arg("P"), py::arg("eps"), py::arg("on_ulps"),
          py::arg("side_ulps"),
          "engine_sides(normals, centroids, vmax, P, eps, on_ulps, side_ulps) -> (side, band, "
          "undecided), each (R, N): exactff.predicates.engine_sides before its exact tests");
}
