// Python module exactff.area._pair: an occluded pair's compiled path (pair.h). Arrays in
// and out, the GIL released around the computation; no math.

#include <cstdint>
#include <stdexcept>

#include "bind_arrays.h"
#include "pair.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;

namespace {

py::tuple event_lines(Array<double> W, Array<std::int64_t> start, Array<std::int64_t> solid,
                      Array<double> nP, double dP, Array<double> frame, Array<double> c,
                      double radius, Array<double> nQ, Array<double> q0, Array<double> RQ,
                      Array<double> Q2, bool shortcuts, double ray_parallel,
                      double event_parallel) {
    const std::int64_t n = start.size() - 1;
    if (W.ndim() != 2 || W.shape(1) != 3 || n < 1 || nP.size() != 3 || frame.size() != 9 ||
        c.size() != 3 || nQ.size() != 3 || q0.size() != 3 || RQ.size() != 6 ||
        Q2.ndim() != 2 || Q2.shape(1) != 2 || (solid.size() != 0 && solid.size() != n))
        throw std::invalid_argument("event_lines: arrays of the wrong shapes");
    const std::int64_t* s = start.data();
    for (std::int64_t k = 0; k < n; ++k)
        if (s[k] < 0 || s[k + 1] - s[k] < 3 || s[k + 1] > W.shape(0))
            throw std::out_of_range("event_lines: start out of range or a polygon of < 3 "
                                    "vertices");
    exactff::EventArgs a;
    a.W = W.data();
    a.start = s;
    a.n = n;
    a.solid = solid.size() ? solid.data() : nullptr;
    a.nP = nP.data();
    a.frame = frame.data();
    a.c = c.data();
    a.dP = dP;
    a.radius = radius;
    a.nQ = nQ.data();
    a.q0 = q0.data();
    a.RQ = RQ.data();
    a.Q2 = Q2.data();
    a.n_q2 = Q2.shape(0);
    a.shortcuts = shortcuts;
    a.ray_parallel = ray_parallel;
    a.event_parallel = event_parallel;
    exactff::EventResult r;
    {
        py::gil_scoped_release release;
        r = exactff::event_lines(a);
    }
    py::array_t<double> seg = as_array(r.segments);
    return py::make_tuple(seg.reshape({py::ssize_t(r.segments.size() / 4), py::ssize_t(2),
                                       py::ssize_t(2)}),
                          r.culled_events, r.solid_events);
}

py::tuple cut_cells(Array<double> P2, Array<double> segments, double step, double merge,
                    double sliver) {
    if (P2.ndim() != 2 || P2.shape(1) != 2 || P2.shape(0) < 3 ||
        (segments.size() != 0 && (segments.ndim() != 3 || segments.shape(1) != 2 ||
                                  segments.shape(2) != 2)))
        throw std::invalid_argument("cut_cells: P2 (k >= 3, 2), segments (m, 2, 2) expected");
    const std::int64_t m = segments.size() / 4;
    exactff::CellResult r;
    {
        py::gil_scoped_release release;
        r = exactff::cut_cells(P2.data(), P2.shape(0), segments.data(), m, step, merge, sliver);
    }
    py::array_t<double> tri = as_array(r.triangles);
    return py::make_tuple(tri.reshape({py::ssize_t(r.triangles.size() / 6), py::ssize_t(3),
                                       py::ssize_t(2)}),
                          as_array(r.areas), r.ok);
}

}  // namespace

PYBIND11_MODULE(_pair, m) {
    m.doc() = "An occluded pair of an area row, compiled (exactff.area).";
    m.def("event_lines", &event_lines, py::arg("W"), py::arg("start"), py::arg("solid"),
          py::arg("nP"), py::arg("dP"), py::arg("frame"), py::arg("c"), py::arg("radius"),
          py::arg("nQ"), py::arg("q0"), py::arg("RQ"), py::arg("Q2"), py::arg("shortcuts"),
          py::arg("ray_parallel"), py::arg("event_parallel"),
          "event_lines(...) -> (segments (m, 2, 2), culled_events, solid_events): the pair's "
          "vertex-edge events as segments of the emitter's plane (pair.h)");
    m.def("cut_cells", &cut_cells, py::arg("P2"), py::arg("segments"), py::arg("step"),
          py::arg("merge"), py::arg("sliver"),
          "cut_cells(P2, segments, step, merge, sliver) -> (triangles (t, 3, 2), areas, ok): the "
          "emitter cut along the event lines (pair.h)");
}
