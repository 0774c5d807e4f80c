// Python module exactff.visibility._svbsp: the visibility core (core.h) and the BSP build
// (bsp_build.h). Arrays in and out, the GIL released around the computation; no math.

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "bind_arrays.h"
#include "bsp_build.h"
#include "core.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;
using exactff::bind::to_vector;

namespace {

exactff::Core make_core(Array<double> vertices, Array<int64_t> start, Array<int64_t> count,
                        Array<int64_t> source, Array<int64_t> front, Array<int64_t> back,
                        Array<int64_t> here_start, Array<int64_t> here_front,
                        Array<int64_t> here_behind, int64_t n_sources, double band, double c1,
                        double c2, double split, Array<double> vertex_errors) {
    return exactff::Core(to_vector(vertices), to_vector(start), to_vector(count),
                         to_vector(source), to_vector(front), to_vector(back),
                         to_vector(here_start), to_vector(here_front), to_vector(here_behind),
                         n_sources, band, c1, c2, split, to_vector(vertex_errors));
}

py::tuple row(const exactff::Core& core, Array<double> point, Array<double> normal,
              Array<int8_t> node_side, Array<int8_t> source_side, bool two_sided, bool cull,
              int64_t box_budget, int64_t tiles, double rtol, double floor, bool eq3,
              bool sphere) {
    if (point.size() != 3 || normal.size() != 3)
        throw std::invalid_argument("point and normal must have 3 coordinates");
    if (node_side.size() != core.nodes())
        throw std::invalid_argument("node_side must have one entry per BSP node");
    if (source_side.size() != core.n_sources())
        throw std::invalid_argument("source_side must have one entry per polygon");
    if (!(rtol >= 0) || !(floor >= 0) || !std::isfinite(floor))
        throw std::invalid_argument("rtol and floor must be finite and >= 0");
    exactff::RowResult r;
    {
        py::gil_scoped_release release;
        r = core.row(point.data(), normal.data(), node_side.data(), source_side.data(),
                     two_sided, cull, box_budget, tiles, rtol, floor, eq3, sphere);
    }
    const exactff::RowStats& st = r.stats;
    py::dict d;
    d["fragments"] = st.fragments;
    d["visible_pieces"] = st.visible;
    d["hidden_pieces"] = st.hidden;
    d["splits"] = st.splits;
    d["subtrees_culled"] = st.subtrees_culled;
    d["fragments_culled"] = st.fragments_culled;
    d["box_tests"] = st.box_tests;
    d["shadow_planes"] = st.shadow_planes;
    d["node_visits"] = st.node_visits;
    d["near_tests"] = st.near_tests;
    d["exact_tests"] = st.exact_tests;
    d["quad_pieces"] = st.quad_pieces;
    d["pieces_held"] = st.pieces_held;
    d["unattributed_bound"] = static_cast<double>(st.unattributed);
    d["shadows_left_out"] = st.slivers[0] + st.slivers[1] + st.slivers[2] + st.slivers[3];
    d["kernel_shadows"] = st.kernels;
    d["omitted_sides"] = st.omitted_sides;
    d["collapsed"] = st.collapsed;
    d["tiles_cut"] = st.tiles_cut;
    d["repeated_sides"] = st.repeated_sides;
    d["cover_proofs"] = st.cover_proofs;
    d["cover_cells"] = st.cover_cells;
    d["cover_visits"] = st.cover_visits;
    d["fragments_covered"] = st.fragments_covered;
    d["fragments_behind"] = st.fragments_behind;
    d["subtrees_covered"] = st.subtrees_covered;
    d["covered"] = st.covered;
    d["leaks"] = static_cast<int64_t>(st.leaks.size());
    d["working_bytes"] = st.working_bytes;
    return py::make_tuple(as_array(r.F), as_array(r.E), as_array(r.B), as_array(r.G), d);
}

py::tuple build_bsp_arrays(Array<double> V, Array<int64_t> start, Array<double> normals,
                           Array<double> offsets, int64_t candidates, int64_t sample,
                           int64_t axis_min, double axis_imbalance, double band_ulps,
                           double snap, uint64_t seed) {
    int64_t n = int64_t(start.size()) - 1;
    if (n < 0 || normals.size() != 3 * n || offsets.size() != n ||
        V.size() != 3 * start.data()[n])
        throw std::invalid_argument("build_bsp_arrays: inconsistent array sizes");
    if (candidates < 1 || sample < 1)
        throw std::invalid_argument("build_bsp_arrays: candidates and sample must be >= 1");
    exactff::BspArrays b;
    {
        py::gil_scoped_release release;
        b = exactff::build_bsp(V.data(), start.data(), n, normals.data(), offsets.data(),
                               size_t(candidates), size_t(sample), size_t(axis_min),
                               axis_imbalance, band_ulps, snap, seed);
    }
    py::array_t<double> nn({py::ssize_t(b.node_d.size()), py::ssize_t(3)});
    std::copy(b.node_n.begin(), b.node_n.end(), nn.mutable_data());
    py::array_t<double> vv({py::ssize_t(b.live_verts.size() / 3), py::ssize_t(3)});
    std::copy(b.live_verts.begin(), b.live_verts.end(), vv.mutable_data());
    return py::make_tuple(nn, as_array(b.node_d), as_array(b.front), as_array(b.back),
                          as_array(b.here_start), as_array(b.here), vv, as_array(b.live_start),
                          as_array(b.live_source), as_array(b.whole).attr("astype")("bool"),
                          b.splits, as_array(b.live_err));
}

}  // namespace

PYBIND11_MODULE(_svbsp, m) {
    m.doc() = "Compiled visibility core: shadow-volume BSP rows (exactff.visibility.compiled)";
    py::class_<exactff::Core>(m, "Core")
        .def(py::init(&make_core), py::arg("vertices"), py::arg("start"), py::arg("count"),
             py::arg("source"), py::arg("front"), py::arg("back"), py::arg("here_start"),
             py::arg("here_front"), py::arg("here_behind"), py::arg("n_sources"),
             py::arg("band"), py::arg("c1"), py::arg("c2"), py::arg("split"),
             py::arg("vertex_errors"))
        .def("row", &row, py::arg("point"), py::arg("normal"), py::arg("node_side"),
             py::arg("source_side"), py::arg("two_sided"), py::arg("cull"),
             py::arg("box_budget"), py::arg("tiles"), py::arg("rtol"), py::arg("floor"),
             py::arg("eq3") = false,
             py::arg("sphere") = false)
        .def_property_readonly("nodes", &exactff::Core::nodes)
        .def_property_readonly("pieces", &exactff::Core::pieces)
        .def_property_readonly("unit_roundoff", &exactff::Core::unit_roundoff);
    m.def("build_bsp_arrays", &build_bsp_arrays, py::arg("V"), py::arg("start"),
          py::arg("normals"), py::arg("offsets"), py::arg("candidates"), py::arg("sample"),
          py::arg("axis_min"), py::arg("axis_imbalance"), py::arg("band_ulps"), py::arg("snap"),
          py::arg("seed"),
          "The scene's BSP tree as arrays (exactff.visibility.bsp.build_bsp, "
          "engine='compiled')");
}
