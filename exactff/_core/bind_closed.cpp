// Python module exactff.area._closed: the unoccluded area pair in closed form
// (closed_form.h) and its dilogarithm (dilog.h). Arrays in and out, the GIL released
// around the computation; no math.

#include <complex>
#include <cstdint>
#include <stdexcept>

#include "bind_arrays.h"
#include "closed_form.h"
#include "dilog.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;

namespace {

exactff::area::ClosedFormConstants constants(double thin, double tiny, double ulps, double eps,
                                              double near) {
    exactff::area::ClosedFormConstants k;
    k.thin = thin;
    k.tiny = tiny;
    k.ulps = ulps;
    k.eps = eps;
    k.near = near;
    return k;
}

py::array_t<std::complex<double>> li2(Array<std::complex<double>> z) {
    py::array_t<std::complex<double>> out(z.size());
    const std::complex<double>* in = z.data();
    std::complex<double>* o = out.mutable_data();
    const py::ssize_t n = z.size();
    {
        py::gil_scoped_release release;
        for (py::ssize_t i = 0; i < n; ++i) o[i] = exactff::area::li2(in[i]);
    }
    return out;
}

py::tuple edge_log_integrals(Array<double> a, Array<double> e, Array<double> b, Array<double> f,
                             double thin, double tiny, double ulps, double eps, double near) {
    const py::ssize_t n = a.size() / 3;
    if (a.ndim() != 2 || a.shape(1) != 3 || e.size() != 3 * n || b.size() != 3 * n ||
        f.size() != 3 * n)
        throw std::invalid_argument("edge_log_integrals: a, e, b, f (N, 3) expected");
    py::array_t<double> J(n), M(n);
    const auto k = constants(thin, tiny, ulps, eps, near);
    {
        py::gil_scoped_release release;
        exactff::area::edge_log_integrals(a.data(), e.data(), b.data(), f.data(), n, k,
                                          J.mutable_data(), M.mutable_data());
    }
    return py::make_tuple(J, M);
}

py::tuple row_pairs(Array<double> VP, Array<std::int64_t> po, Array<double> VQ,
                    Array<std::int64_t> qo, Array<double> inv, Array<double> scale, double thin,
                    double tiny, double ulps, double eps, double near) {
    const py::ssize_t m = inv.size();
    if (VP.ndim() != 2 || VP.shape(1) != 3 || VQ.ndim() != 2 || VQ.shape(1) != 3 ||
        po.size() != m + 1 || qo.size() != m + 1 || scale.size() != m)
        throw std::invalid_argument(
            "row_pairs: VP (N, 3), VQ (N', 3), po and qo (m + 1,), inv and scale (m,) expected");
    exactff::bind::check_polygon_starts(po, VP.shape(0), "row_pairs");
    exactff::bind::check_polygon_starts(qo, VQ.shape(0), "row_pairs");
    exactff::area::RowPairs r;
    const auto k = constants(thin, tiny, ulps, eps, near);
    {
        py::gil_scoped_release release;
        r = exactff::area::row_pairs(VP.data(), po.data(), VQ.data(), qo.data(), m, inv.data(),
                                     scale.data(), k);
    }
    return py::make_tuple(as_array(r.value), as_array(r.estimate), as_array(r.owner),
                          as_array(r.ip), as_array(r.iq), as_array(r.ef), as_array(r.J),
                          as_array(r.c));
}

}  // namespace

PYBIND11_MODULE(_closed, m) {
    m.doc() = "The unoccluded area pair in closed form (exactff.area.closed_form) and its "
              "dilogarithm";
    m.def("li2", &li2, py::arg("z"),
          "li2(z) -> Li2(z), the dilogarithm of each complex z (principal branch)");
    m.def("edge_log_integrals", &edge_log_integrals, py::arg("a"), py::arg("e"), py::arg("b"),
          py::arg("f"), py::arg("thin"), py::arg("tiny"), py::arg("ulps"), py::arg("eps"),
          py::arg("near"),
          "edge_log_integrals(a, e, b, f, thin, tiny, ulps, eps, near) -> (J, M): the edge-pair "
          "integrals and "
          "their terms' magnitudes (exactff.area.edge_integrals.edge_log_integrals)");
    m.def("row_pairs", &row_pairs, py::arg("VP"), py::arg("po"), py::arg("VQ"), py::arg("qo"),
          py::arg("inv"), py::arg("scale"), py::arg("thin"), py::arg("tiny"), py::arg("ulps"),
          py::arg("eps"), py::arg("near"),
          "row_pairs(VP, po, VQ, qo, inv, scale, thin, tiny, ulps, eps, near) -> (values, "
          "estimates, owner, ip, iq, ef, J, c): a row's pairs in closed form, and their kept "
          "edge pairs (exactff.area.closed_form.unoccluded_pairs)");
}
