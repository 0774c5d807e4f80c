// Python module exactff.methods._zbuffer: the discrete methods' z-buffer (zbuffer.h), a
// row's ZBuffer and its scans, the two clippers and a row's sums. The arrays' shapes
// and ranges checked, the GIL released around the library's calls; no math.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bind_arrays.h"
#include "zbuffer.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::zbuffer::Bucket;
using exactff::zbuffer::Buffer;
using exactff::zbuffer::Chart;
using exactff::zbuffer::Chunks;
using exactff::zbuffer::Clipped;
using exactff::zbuffer::Face;
using exactff::zbuffer::Grid;
using exactff::zbuffer::i64;

namespace {

// the arrays the functions take: C-ordered, converted from any dtype (except the depth
// buffer, which must be written in place)
using Doubles = Array<double>;
using Ints = Array<i64>;
using Bools = Array<bool>;

i64 check_vertices(const Doubles& V, const Ints& counts) {
    if (V.ndim() != 3 || V.shape(2) != 3)
        throw std::invalid_argument("V must have shape (M, K, 3)");
    const i64 M = V.shape(0);
    if (counts.ndim() != 1 || counts.shape(0) != M)
        throw std::invalid_argument("counts must have shape (M,)");
    for (i64 m = 0; m < M; ++m)
        if (counts.data()[m] > V.shape(1) || counts.data()[m] < 0)
            throw std::invalid_argument("counts out of range");
    return M;
}

i64 check_bucket(const Doubles& V, const Ints& counts, const Doubles& planes, const Doubles& eu,
                 const Doubles& ev, const Doubles& ew) {
    const i64 M = check_vertices(V, counts);
    if (planes.ndim() != 2 || planes.shape(0) != 4 || planes.shape(1) != 3)
        throw std::invalid_argument("planes must have shape (4, 3)");
    if (eu.size() != 3 || ev.size() != 3 || ew.size() != 3)
        throw std::invalid_argument("eu, ev, ew must have shape (3,)");
    return M;
}

i64 check_face_bucket(const Doubles& V, const Ints& counts, const Doubles& R,
                      const Doubles& planes) {
    const i64 M = check_vertices(V, counts);
    if (R.ndim() != 2 || R.shape(0) != 3 || R.shape(1) != 3)
        throw std::invalid_argument("R must have shape (3, 3)");
    if (planes.ndim() != 2 || planes.shape(1) != 3)
        throw std::invalid_argument("planes must have shape (P, 3)");
    for (i64 k = 0; k < planes.size(); ++k) {
        const double h = planes.data()[k];
        if (h != 0 && h != 1 && h != -1)
            throw std::invalid_argument("planes' entries must be 0, 1 or -1");
    }
    return M;
}

// the layout's cell of each grid cell: one row per scanline, one column per centre
void check_table(const Ints& table, i64 rows, i64 cols) {
    if (table.ndim() != 2 || table.shape(0) != rows || table.shape(1) != cols)
        throw std::invalid_argument("table must have shape (scanlines, centres): (" +
                                    std::to_string(rows) + ", " + std::to_string(cols) + ")");
}

// a bucket's arrays (g_ids: the live indices, where the call has them)
Bucket bucket_of(const Doubles& V, const Ints& counts, const i64* g_ids = nullptr) {
    return Bucket{V.data(), V.shape(0), V.shape(1), counts.data(), g_ids};
}

Chart chart_of(const Doubles& planes, const Doubles& eu, const Doubles& ev, const Doubles& ew,
               bool side) {
    return Chart{planes.data(), eu.data(), ev.data(), ew.data(), side};
}

Face face_of(const Doubles& R, const Doubles& planes, double scale) {
    return Face{R.data(), planes.data(), planes.shape(0), scale};
}

py::tuple clipped_tuple(const Clipped& c) {
    const i64 L = static_cast<i64>(c.live.size());
    py::array_t<i64> live(L), cl(L);
    py::array_t<double> UV({L, c.K, static_cast<i64>(2)});
    std::copy(c.live.begin(), c.live.end(), live.mutable_data());
    std::copy(c.cl.begin(), c.cl.end(), cl.mutable_data());
    std::copy(c.UV.begin(), c.UV.end(), UV.mutable_data());
    return py::make_tuple(live, UV, cl);
}

// A row's z-buffer (exactff.methods._zbuffer.ZBuffer): the row's arrays kept alive
// for the library's ZBuffer, which reads them
class PyZBuffer {
  public:
    PyZBuffer(Doubles D, Doubles Dnorm, Doubles nl, Doubles dl, Doubles band, Ints prio,
              Doubles V, Ints offsets, Doubles N, Doubles Dp, Ints ids, double coplanar_ulps,
              double tie_slack_ulps, double clip_meet_ulps, double chart_edge_ulps)
        : D_(D), Dnorm_(Dnorm), nl_(nl), dl_(dl), band_(band), prio_(prio), V_(V),
          offsets_(offsets), N_(N), Dp_(Dp), ids_(ids),
          zb_(row_data(coplanar_ulps, tie_slack_ulps, clip_meet_ulps, chart_edge_ulps)) {}

    void face(Doubles UV, Ints cl, Ints src, Doubles uc, Doubles vc, Ints table,
              py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        if (UV.ndim() != 3 || UV.shape(2) != 2)
            throw std::invalid_argument("UV must have shape (M, K, 2)");
        const i64 M = UV.shape(0), K = UV.shape(1);
        if (cl.shape(0) != M || src.shape(0) != M)
            throw std::invalid_argument("cl and src must have shape (M,)");
        const Grid g = grid(uc, vc, table);
        const Buffer buf = writable(best_t, best);
        for (i64 m = 0; m < M; ++m) {
            if (src.data()[m] < 0 || src.data()[m] >= n_live_)
                throw std::invalid_argument("src out of range");
            if (cl.data()[m] > K) throw std::invalid_argument("cl exceeds K");
        }
        py::gil_scoped_release release;
        zb_.face(UV.data(), M, K, cl.data(), src.data(), g, buf, Chunks{pair_chunk, depth_chunk});
    }

    void chart_face(Doubles V, Ints counts, Ints g_ids, Doubles planes, Doubles eu, Doubles ev,
                    Doubles ew, bool side, Doubles uc, Doubles vc, Ints table,
                    py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        check_ids(g_ids, check_bucket(V, counts, planes, eu, ev, ew));
        const Grid g = grid(uc, vc, table);
        const Buffer buf = writable(best_t, best);
        py::gil_scoped_release release;
        zb_.chart_face(bucket_of(V, counts, g_ids.data()), chart_of(planes, eu, ev, ew, side), g,
                       buf, Chunks{pair_chunk, depth_chunk});
    }

    void candidates(Ints cell, Ints src, py::array best_t, py::array best, i64 depth_chunk) {
        const Buffer buf = writable(best_t, best);
        const i64 n = cell.shape(0);
        if (src.shape(0) != n) throw std::invalid_argument("cell and src differ in length");
        const i64* c = cell.data();
        const i64* s = src.data();
        for (i64 k = 0; k < n; ++k)
            if (c[k] < 0 || c[k] >= n_cells_ || s[k] < 0 || s[k] >= n_live_)
                throw std::invalid_argument("cell or src out of range");
        py::gil_scoped_release release;
        zb_.candidates(c, s, n, buf, depth_chunk);
    }

    void clipped_face(Doubles V, Ints counts, Ints g_ids, Doubles R, Doubles planes,
                      double scale, Doubles uc, Doubles vc, Ints table,
                      py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        check_face_bucket(V, counts, R, planes);
        check_ids(g_ids, V.shape(0));
        const Grid g = grid(uc, vc, table);
        const Buffer buf = writable(best_t, best);
        py::gil_scoped_release release;
        zb_.clipped_face(bucket_of(V, counts, g_ids.data()), face_of(R, planes, scale), g, buf,
                         Chunks{pair_chunk, depth_chunk});
    }

    void polar(Doubles V, Ints counts, Ints g_ids, Doubles R, Doubles planes, double scale,
               Doubles radii, Doubles cosv, Doubles sinv,
               py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        check_face_bucket(V, counts, R, planes);
        check_ids(g_ids, V.shape(0));
        const i64 S = cosv.shape(0), nr = radii.shape(0);
        if (sinv.shape(0) != S || S < 1) throw std::invalid_argument("cos and sin: one per sector");
        if (nr * S != n_cells_) throw std::invalid_argument("rings x sectors must be the cells");
        const Buffer buf = writable(best_t, best);
        py::gil_scoped_release release;
        zb_.polar(bucket_of(V, counts, g_ids.data()), face_of(R, planes, scale), radii.data(), nr,
                  cosv.data(), sinv.data(), S, buf, Chunks{pair_chunk, depth_chunk});
    }

    py::array_t<i64> disk(Doubles V, Ints counts, Ints g_ids, Doubles xc, Doubles yc,
                          Ints table, py::array best_t, py::array best, i64 pair_chunk,
                          i64 depth_chunk, double near_rel, bool after_near) {
        check_vertices(V, counts);
        check_ids(g_ids, V.shape(0));
        const Grid g = grid(xc, yc, table);
        const Buffer buf = writable(best_t, best);
        std::vector<i64> near;
        {
            py::gil_scoped_release release;
            near = zb_.disk(bucket_of(V, counts, g_ids.data()), g, buf,
                            Chunks{pair_chunk, depth_chunk}, near_rel, after_near);
        }
        return exactff::bind::as_array(near);
    }

    bool chart_rays(Doubles V, Ints counts, Ints g_ids, Doubles planes, Doubles eu, Doubles ev,
                    Doubles ew, bool side, Ints cells, Doubles cu, Doubles cv,
                    i64 nb, double v_lo, Ints order, Ints starts,
                    py::array best_t, py::array best, i64 pair_chunk, i64 long_polygon) {
        const i64 M = check_bucket(V, counts, planes, eu, ev, ew);
        check_ids(g_ids, M);
        const i64 n = cells.shape(0);
        if (cu.shape(0) != n || cv.shape(0) != n || order.shape(0) != n)
            throw std::invalid_argument("cells, cu, cv, order: one per direction");
        if (nb < 1 || starts.shape(0) != nb * nb + 1)
            throw std::invalid_argument("starts must have nb * nb + 1 entries");
        for (i64 k = 0; k < n; ++k)
            if (cells.data()[k] < 0 || cells.data()[k] >= n_cells_ || order.data()[k] < 0 ||
                order.data()[k] >= n)
                throw std::invalid_argument("cells or order out of range");
        for (i64 k = 0; k <= nb * nb; ++k)
            if (starts.data()[k] < 0 || starts.data()[k] > n ||
                (k > 0 && starts.data()[k] < starts.data()[k - 1]))
                throw std::invalid_argument("starts must be non-decreasing within [0, n]");
        const Buffer buf = writable(best_t, best);
        py::gil_scoped_release release;
        return zb_.chart_rays(bucket_of(V, counts, g_ids.data()),
                              chart_of(planes, eu, ev, ew, side), cells.data(), cu.data(),
                              cv.data(), nb, v_lo, order.data(), starts.data(), buf, pair_chunk,
                              long_polygon);
    }

    // whether live polygons a[k] and b[k] are coplanar (the BSP tree's rule)
    py::array_t<bool> coplanar_many(Ints a, Ints b) {
        const i64 n = a.shape(0);
        py::array_t<bool> out(n);
        bool* o = out.mutable_data();
        for (i64 k = 0; k < n; ++k) o[k] = zb_.coplanar(a.data()[k], b.data()[k]);
        return out;
    }

  private:
    // the row's arrays checked, as the library's RowData
    exactff::zbuffer::RowData row_data(double coplanar_ulps, double tie_slack_ulps,
                                       double clip_meet_ulps, double chart_edge_ulps) {
        if (D_.ndim() != 2 || D_.shape(1) != 3)
            throw std::invalid_argument("D must have shape (C, 3)");
        n_cells_ = D_.shape(0);
        n_live_ = dl_.shape(0);
        if (n_cells_ >= (i64(1) << 31) || n_live_ >= (i64(1) << 31))
            throw std::invalid_argument("at most 2**31 - 1 cells and live polygons");
        if (Dnorm_.shape(0) != n_cells_)
            throw std::invalid_argument("Dnorm must have shape (C,)");
        if (nl_.ndim() != 2 || nl_.shape(0) != n_live_ || nl_.shape(1) != 3 ||
            band_.shape(0) != n_live_ || prio_.shape(0) != n_live_ || ids_.shape(0) != n_live_)
            throw std::invalid_argument("nl, dl, band, prio, ids: one row per live polygon");
        if (V_.ndim() != 2 || V_.shape(1) != 3 || N_.ndim() != 2 || N_.shape(1) != 3 ||
            offsets_.shape(0) != N_.shape(0) + 1 || Dp_.shape(0) != N_.shape(0))
            throw std::invalid_argument("V, offsets, N, Dp: the scene's polygons and planes");
        return exactff::zbuffer::RowData{
            D_.data(), Dnorm_.data(), nl_.data(), dl_.data(), band_.data(), prio_.data(),
            V_.data(), offsets_.data(), N_.data(), Dp_.data(), ids_.data(), n_cells_, n_live_,
            coplanar_ulps, tie_slack_ulps, clip_meet_ulps, chart_edge_ulps};
    }

    static Grid grid(const Doubles& u, const Doubles& v, const Ints& table) {
        check_table(table, u.shape(0), v.shape(0));
        return Grid{u.data(), u.shape(0), v.data(), v.shape(0), table.data()};
    }

    void check_ids(const Ints& g_ids, i64 M) const {
        if (g_ids.ndim() != 1 || g_ids.shape(0) != M)
            throw std::invalid_argument("g_ids must have shape (M,)");
        for (i64 m = 0; m < M; ++m)
            if (g_ids.data()[m] < 0 || g_ids.data()[m] >= n_live_)
                throw std::invalid_argument("g_ids out of range");
    }

    void check_buffer(const py::array& best_t, const py::array& best) const {
        if (!best_t.dtype().is(py::dtype::of<double>()) || !best.dtype().is(py::dtype::of<i64>()))
            throw std::invalid_argument("best_t and best must be float64 and int64");
        if (best_t.ndim() != 1 || best_t.shape(0) != n_cells_ || best.ndim() != 1 ||
            best.shape(0) != n_cells_)
            throw std::invalid_argument("best_t and best must have shape (C,)");
        if (!(best_t.flags() & py::array::c_style) || !(best.flags() & py::array::c_style) ||
            !best_t.writeable() || !best.writeable())
            throw std::invalid_argument("best_t and best must be writeable and contiguous");
    }

    // the depth buffer, checked, as the library's Buffer
    Buffer writable(py::array& best_t, py::array& best) const {
        check_buffer(best_t, best);
        return Buffer{static_cast<double*>(best_t.mutable_data()),
                      static_cast<i64*>(best.mutable_data())};
    }

    Doubles D_, Dnorm_, nl_, dl_, band_;
    Ints prio_;
    Doubles V_;
    Ints offsets_;
    Doubles N_, Dp_;
    Ints ids_;
    i64 n_cells_ = 0, n_live_ = 0;
    exactff::zbuffer::ZBuffer zb_;
};

py::tuple face_clip(Doubles V, Ints counts, Doubles R, Doubles planes, double scale,
                    double clip_meet_ulps) {
    check_face_bucket(V, counts, R, planes);
    Clipped c;
    {
        py::gil_scoped_release release;
        exactff::zbuffer::clip_face(bucket_of(V, counts), face_of(R, planes, scale),
                                    clip_meet_ulps, c);
    }
    return clipped_tuple(c);
}

py::tuple chart_clip(Doubles V, Ints counts, Doubles planes, Doubles eu, Doubles ev, Doubles ew,
                     bool side, double clip_meet_ulps, double chart_edge_ulps) {
    check_bucket(V, counts, planes, eu, ev, ew);
    Clipped c;
    {
        py::gil_scoped_release release;
        exactff::zbuffer::clip_chart(bucket_of(V, counts), chart_of(planes, eu, ev, ew, side),
                                     clip_meet_ulps, chart_edge_ulps, c);
    }
    return clipped_tuple(c);
}

py::tuple row_sums(Ints best, Ints ids, Bools receives, Doubles weights, i64 n) {
    const i64 C = best.shape(0), L = ids.shape(0);
    if (weights.shape(0) != C) throw std::invalid_argument("best and weights differ in length");
    if (receives.shape(0) != n) throw std::invalid_argument("receives must have shape (n,)");
    for (i64 k = 0; k < L; ++k)
        if (ids.data()[k] < 0 || ids.data()[k] >= n)
            throw std::invalid_argument("ids out of range");
    py::array_t<double> F(n);
    i64 hit;
    {
        py::gil_scoped_release release;
        hit = exactff::zbuffer::row_sums(best.data(), C, ids.data(), L, receives.data(),
                                         weights.data(), n, F.mutable_data());
    }
    if (hit < 0) throw std::invalid_argument("best out of range");
    return py::make_tuple(F, hit);
}

py::tuple live_local(Doubles V, Ints counts, Bools alive, Doubles p, Doubles R) {
    const i64 M = check_vertices(V, counts), K = V.shape(1);
    if (alive.ndim() != 1 || alive.shape(0) != M)
        throw std::invalid_argument("alive must have shape (M,)");
    if (p.size() != 3 || R.ndim() != 2 || R.shape(0) != 3 || R.shape(1) != 3)
        throw std::invalid_argument("p must have shape (3,) and R (3, 3)");
    std::vector<i64> live;
    std::vector<double> local;
    {
        py::gil_scoped_release release;
        exactff::zbuffer::live_local(V.data(), M, K, counts.data(), alive.data(), p.data(),
                                     R.data(), live, local);
    }
    py::array_t<double> out({static_cast<i64>(live.size()), K, static_cast<i64>(3)});
    std::copy(local.begin(), local.end(), out.mutable_data());
    return py::make_tuple(exactff::bind::as_array(live), out);
}

// the directions (n, 3), checked
i64 check_directions(const Doubles& D) {
    if (D.ndim() != 2 || D.shape(1) != 3) throw std::invalid_argument("D must have shape (n, 3)");
    return D.shape(0);
}

py::tuple cosine_directions(Doubles q1, Doubles q2) {
    const i64 n = q1.size();
    if (q1.ndim() != 1 || q2.ndim() != 1 || q2.size() != n)
        throw std::invalid_argument("q1 and q2 must have shape (n,)");
    py::array_t<double> D({n, static_cast<i64>(3)}), norms(n);
    {
        py::gil_scoped_release release;
        exactff::zbuffer::cosine_directions(q1.data(), q2.data(), n, D.mutable_data(),
                                            norms.mutable_data());
    }
    return py::make_tuple(D, norms);
}

py::array_t<double> direction_norms(Doubles D) {
    const i64 n = check_directions(D);
    py::array_t<double> norms(n);
    exactff::zbuffer::direction_norms(D.data(), n, norms.mutable_data());
    return norms;
}

// (Dp, norms, slot, charts): the directions renumbered (Dp[slot] = D), the norms of Dp,
// and per non-empty chart (chart, ids, cu, cv, nb, v_lo, order, starts) as chart_rays
// takes them (ids: the chart's directions' indices into Dp, order: the identity)
py::tuple ray_charts(Doubles D, Ints axis, Doubles sign_w, double margin) {
    const i64 n = check_directions(D);
    if (axis.ndim() != 2 || axis.shape(0) != 5 || axis.shape(1) != 3 || sign_w.size() != 5)
        throw std::invalid_argument("axis must have shape (5, 3) and sign_w (5,)");
    for (i64 k = 0; k < 15; ++k)
        if (axis.data()[k] < 0 || axis.data()[k] > 2)
            throw std::invalid_argument("axis: components 0, 1 or 2");
    std::vector<exactff::zbuffer::RayChart> charts;
    py::array_t<i64> slot(n);
    py::array_t<double> Dp({n, static_cast<i64>(3)}), norms(n);
    {
        py::gil_scoped_release release;
        i64* sl = slot.mutable_data();
        exactff::zbuffer::ray_charts(D.data(), n, axis.data(), sign_w.data(), margin, charts, sl);
        double* P = Dp.mutable_data();
        for (i64 k = 0; k < n; ++k)
            for (int i = 0; i < 3; ++i) P[3 * sl[k] + i] = D.data()[3 * k + i];
        exactff::zbuffer::direction_norms(P, n, norms.mutable_data());
    }
    py::list out;
    for (const auto& rc : charts) {
        py::array_t<i64> ids(rc.count), order(rc.count);
        for (i64 k = 0; k < rc.count; ++k) {
            ids.mutable_data()[k] = rc.offset + k;
            order.mutable_data()[k] = k;
        }
        out.append(py::make_tuple(rc.chart, ids, exactff::bind::as_array(rc.cu),
                                  exactff::bind::as_array(rc.cv), rc.nb, rc.v_lo, order,
                                  exactff::bind::as_array(rc.starts)));
    }
    return py::make_tuple(Dp, norms, slot, out);
}

}  // namespace

PYBIND11_MODULE(_zbuffer, m) {
    m.doc() = "The compiled z-buffer of the discrete methods: scan conversion and depth test.";
    py::class_<PyZBuffer>(m, "ZBuffer")
        .def(py::init<Doubles, Doubles, Doubles, Doubles, Doubles, Ints, Doubles, Ints, Doubles,
                      Doubles, Ints, double, double, double, double>(),
             py::arg("D"), py::arg("Dnorm"), py::arg("nl"), py::arg("dl"), py::arg("band"),
             py::arg("prio"), py::arg("V"), py::arg("offsets"), py::arg("N"), py::arg("Dp"),
             py::arg("ids"), py::arg("coplanar_ulps"), py::arg("tie_slack_ulps"),
             py::arg("clip_meet_ulps"), py::arg("chart_edge_ulps"))
        .def("face", &PyZBuffer::face, py::arg("UV"), py::arg("cl"), py::arg("src"),
             py::arg("uc"), py::arg("vc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("candidates", &PyZBuffer::candidates, py::arg("cell"), py::arg("src"),
             py::arg("best_t"), py::arg("best"), py::arg("depth_chunk"))
        .def("chart_face", &PyZBuffer::chart_face, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("planes"), py::arg("eu"), py::arg("ev"), py::arg("ew"),
             py::arg("side"), py::arg("uc"), py::arg("vc"), py::arg("table"),
             py::arg("best_t"), py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("clipped_face", &PyZBuffer::clipped_face, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("R"), py::arg("planes"), py::arg("scale"),
             py::arg("uc"), py::arg("vc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("polar", &PyZBuffer::polar, py::arg("V"), py::arg("counts"), py::arg("g_ids"),
             py::arg("R"), py::arg("planes"), py::arg("scale"), py::arg("radii"),
             py::arg("cos"), py::arg("sin"), py::arg("best_t"), py::arg("best"),
             py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("disk", &PyZBuffer::disk, py::arg("V"), py::arg("counts"), py::arg("g_ids"),
             py::arg("xc"), py::arg("yc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"),
             py::arg("near_rel"), py::arg("after_near") = false)
        .def("chart_rays", &PyZBuffer::chart_rays, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("planes"), py::arg("eu"), py::arg("ev"), py::arg("ew"),
             py::arg("side"), py::arg("cells"), py::arg("cu"), py::arg("cv"), py::arg("nb"),
             py::arg("v_lo"), py::arg("order"), py::arg("starts"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("long_polygon"))
        .def("coplanar", &PyZBuffer::coplanar_many, py::arg("a"), py::arg("b"));
    m.def("face_clip", &face_clip, py::arg("V"), py::arg("counts"), py::arg("R"),
          py::arg("planes"), py::arg("scale"), py::arg("clip_meet_ulps"),
          "exactff.methods._raster.FaceClip of one bucket, compiled: (live, UV, cl).");
    m.def("live_local", &live_local, py::arg("V"), py::arg("counts"), py::arg("alive"),
          py::arg("p"), py::arg("R"),
          "ZBufferRow's live polygons of a bucket: (bucket indices, local vertices).");
    m.def("cosine_directions", &cosine_directions, py::arg("q1"), py::arg("q2"),
          "Monte Carlo's cosine-weighted unit directions from uniform samples: (D, norms).");
    m.def("direction_norms", &direction_norms, py::arg("D"),
          "|d| per direction, as np.linalg.norm(D, axis=1): sqrt((x x + y y) + z z).");
    m.def("ray_charts", &ray_charts, py::arg("D"), py::arg("axis"), py::arg("sign_w"),
          py::arg("margin"),
          "Directions sorted into the charts and bucketed: (Dp, norms, slot, charts).");
    m.def("row_sums", &row_sums, py::arg("best"), py::arg("ids"), py::arg("receives"),
          py::arg("weights"), py::arg("n"),
          "A row from its depth buffer: (F, cells that show a polygon); np.bincount's sums.");
    m.def("chart_clip", &chart_clip, py::arg("V"), py::arg("counts"), py::arg("planes"),
          py::arg("eu"), py::arg("ev"), py::arg("ew"), py::arg("side"),
          py::arg("clip_meet_ulps"), py::arg("chart_edge_ulps"),
          "exactff.visibility.charts.chart_clip (margin 0) of one bucket, compiled: "
          "(live, UV, cl).");
}
