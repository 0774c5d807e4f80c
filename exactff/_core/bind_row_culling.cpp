// Python module exactff.area._row_culling: a row's blockers, shaft culling and the hull
// test (row_culling.h). Arrays in and out, the GIL released around the computation; no
// math.

#include <cstdint>
#include <stdexcept>

#include "bind_arrays.h"
#include "row_culling.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;

namespace {

py::tuple row_blockers(Array<double> V, Array<double> lo, Array<double> hi, Array<double> N,
                       std::int64_t i, Array<double> nP, Array<double> p0, Array<std::int64_t> J,
                       Array<double> boxes, Array<double> VP, Array<std::int64_t> po,
                       Array<double> VQ, Array<std::int64_t> qo, double near, double eps,
                       std::int64_t hull_points) {
    const std::int64_t m = J.size();
    if (V.ndim() != 3 || V.shape(2) != 3 || V.shape(1) < 1)
        throw std::invalid_argument("row_blockers: V (n, kmax, 3) expected");
    const std::int64_t n = V.shape(0);
    if (lo.size() != 3 * n || hi.size() != 3 * n || N.size() != 3 * n || nP.size() != 3 ||
        p0.size() != 3 || boxes.size() != 12 * m || po.size() != m + 1 || qo.size() != m + 1 ||
        VP.ndim() != 2 || VP.shape(1) != 3 || VQ.ndim() != 2 || VQ.shape(1) != 3)
        throw std::invalid_argument(
            "row_blockers: lo, hi, N (n, 3), nP, p0 (3,), J (m,), boxes (m, 4, 3), po, qo "
            "(m + 1,), VP, VQ (., 3) expected");
    if (i < 0 || i >= n) throw std::out_of_range("row_blockers: emitter out of range");
    for (std::int64_t a = 0; a < m; ++a)
        if (J.data()[a] < 0 || J.data()[a] >= n)
            throw std::out_of_range("row_blockers: receiver out of range");
    exactff::bind::check_polygon_starts(po, VP.shape(0), "row_blockers");
    exactff::bind::check_polygon_starts(qo, VQ.shape(0), "row_blockers");
    exactff::area::RowCullingArgs a;
    a.V = V.data();
    a.lo = lo.data();
    a.hi = hi.data();
    a.N = N.data();
    a.n = n;
    a.kmax = V.shape(1);
    a.i = i;
    a.nP = nP.data();
    a.p0 = p0.data();
    a.J = J.data();
    a.boxes = boxes.data();
    a.VP = VP.data();
    a.po = po.data();
    a.VQ = VQ.data();
    a.qo = qo.data();
    a.m = m;
    a.near = near;
    a.eps = eps;
    a.hull_points = hull_points;
    exactff::area::RowBlockers r;
    {
        py::gil_scoped_release release;
        r = exactff::area::row_blockers(a);
    }
    return py::make_tuple(as_array(r.blockers), as_array(r.start), as_array(r.boxed),
                          as_array(r.left));
}

}  // namespace

PYBIND11_MODULE(_row_culling, m) {
    m.doc() = "A row's blockers: shaft culling and the hull test (exactff.area.culling)";
    m.def("row_blockers", &row_blockers, py::arg("V"), py::arg("lo"), py::arg("hi"), py::arg("N"),
          py::arg("i"), py::arg("nP"), py::arg("p0"), py::arg("J"), py::arg("boxes"),
          py::arg("VP"), py::arg("po"), py::arg("VQ"), py::arg("qo"), py::arg("near"),
          py::arg("eps"), py::arg("hull_points"),
          "row_blockers(V, lo, hi, N, i, nP, p0, J, boxes, VP, po, VQ, qo, near, eps, "
          "hull_points) -> (blockers, start, boxed, left): pair a's blockers "
          "blockers[start[a]:start[a + 1]], the polygons in its box and those the shaft left");
}
