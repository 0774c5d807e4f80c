// Python module exactff.area._hidden: the hidden pieces (hidden.h). Arrays in and out,
// the GIL released around the computation; no math.

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "bind_arrays.h"
#include "bind_hidden_args.h"
#include "hidden.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;

namespace {

py::tuple hidden_pieces(Array<double> X, Array<double> corners, Array<double> q0,
                        Array<double> nQ, Array<double> RQ, Array<double> blockers,
                        Array<long long> counts, Array<double> normals, Array<long long> groups,
                        double back_face, double edge_on, double vertex_ulps, double sliver_ulps,
                        long long max_pieces, double precise_rtol, double extent,
                        Array<double> parts, Array<long long> part_counts, Array<double> frame,
                        double c1, double c2, double eps, bool rings, double precise_atol,
                        py::object cells) {
    if (X.ndim() != 2 || X.shape(1) != 3)
        throw std::invalid_argument("hidden_pieces: arrays of the wrong shapes");
    exactff::HiddenArgs a;
    a.X = X.data();
    a.n = X.shape(0);
    exactff::bind::set_hidden_geometry(a, "hidden_pieces", corners, q0, nQ, RQ, blockers,
                                       counts, normals, groups, parts, part_counts, frame,
                                       extent);
    a.back_face = back_face;
    a.edge_on = edge_on;
    a.vertex_ulps = vertex_ulps;
    a.sliver_ulps = sliver_ulps;
    a.max_pieces = max_pieces;
    a.precise_rtol = precise_rtol;
    a.precise_atol = precise_atol;
    a.c1 = c1;
    a.c2 = c2;
    a.eps = eps;
    a.rings = rings;
    // each point's cell (hidden.h), or point by point
    Array<long long> cell_ids;
    if (!cells.is_none()) {
        cell_ids = cells.cast<Array<long long>>();
        if (cell_ids.ndim() != 1 || cell_ids.shape(0) != X.shape(0))
            throw std::invalid_argument("hidden_pieces: cells must hold one cell per point");
        a.cells = cell_ids.data();
    }
    exactff::HiddenResult r;
    {
        py::gil_scoped_release release;
        r = exactff::hidden_pieces(a);
    }
    py::array_t<bool> lost(py::ssize_t(r.lost.size()));
    std::copy(r.lost.begin(), r.lost.end(), lost.mutable_data());
    return py::make_tuple(as_array(r.xy, 2), as_array(r.ring_start), as_array(r.ring_point),
                          lost, as_array(r.reach), as_array(r.length), as_array(r.box, 4),
                          as_array(r.moved), as_array(r.dropped), as_array(r.hidden),
                          as_array(r.rounding), r.back_faces);
}

}  // namespace

PYBIND11_MODULE(_hidden, m) {
    m.doc() = "The hidden region of a receiver from many points, as disjoint convex pieces "
              "(exactff.area.occluded).";
    m.def("hidden_pieces", &hidden_pieces, py::arg("X"), py::arg("corners"), py::arg("q0"),
          py::arg("nQ"), py::arg("RQ"), py::arg("blockers"), py::arg("counts"),
          py::arg("normals"), py::arg("groups"), py::arg("back_face"), py::arg("edge_on"),
          py::arg("vertex_ulps"), py::arg("sliver_ulps"), py::arg("max_pieces"),
          py::arg("precise_rtol"), py::arg("extent"), py::arg("parts"), py::arg("part_counts"),
          py::arg("frame"), py::arg("c1"), py::arg("c2"), py::arg("eps"), py::arg("rings"),
          py::arg("precise_atol"), py::arg("cells") = py::none());
}
