// Python module exactff.area._pair: an occluded pair's compiled path (pair.h). Arrays in
// and out, the GIL released around the computation; no math.

#include <cstdint>
#include <memory>
#include <stdexcept>

#include "bind_arrays.h"
#include "bind_hidden_args.h"
#include "hidden.h"
#include "hidden_setup.h"
#include "levels.h"
#include "occluded_pair.h"
#include "pair.h"

namespace py = pybind11;
using exactff::bind::Array;
using exactff::bind::as_array;
using exactff::bind::check_polygon_starts;

namespace {

py::tuple event_lines(Array<double> W, Array<std::int64_t> start, Array<std::int64_t> solid,
                      Array<double> nP, double dP, Array<double> frame, Array<double> c,
                      double radius, Array<double> nQ, Array<double> q0, Array<double> RQ,
                      Array<double> Q2, bool shortcuts, double ray_parallel,
                      double event_parallel, double line_ulps, double eps) {
    const std::int64_t n = start.size() - 1;
    if (W.ndim() != 2 || W.shape(1) != 3 || n < 1 || nP.size() != 3 || frame.size() != 9 ||
        c.size() != 3 || nQ.size() != 3 || q0.size() != 3 || RQ.size() != 6 ||
        Q2.ndim() != 2 || Q2.shape(1) != 2 || (solid.size() != 0 && solid.size() != n))
        throw std::invalid_argument("event_lines: arrays of the wrong shapes");
    check_polygon_starts(start, W.shape(0), "event_lines");
    const std::int64_t* s = start.data();
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
    a.line_ulps = line_ulps;
    a.eps = eps;
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

py::tuple curved_event_lines(Array<double> W, Array<std::int64_t> start,
                             Array<std::int64_t> solid, Array<double> Qc, Array<double> nP,
                             double dP, Array<double> frame, Array<double> c, double radius,
                             double atol, py::dict tol) {
    const std::int64_t n = start.size() - 1;
    if (W.ndim() != 2 || W.shape(1) != 3 || n < 1 || nP.size() != 3 || frame.size() != 9 ||
        c.size() != 3 || Qc.ndim() != 2 || Qc.shape(1) != 3 || Qc.shape(0) < 3 ||
        (solid.size() != 0 && solid.size() != n))
        throw std::invalid_argument("curved_event_lines: arrays of the wrong shapes");
    check_polygon_starts(start, W.shape(0), "curved_event_lines");
    exactff::CurvedArgs a;
    a.W = W.data();
    a.start = start.data();
    a.n = n;
    a.solid = solid.size() ? solid.data() : nullptr;
    a.Qc = Qc.data();
    a.n_q = Qc.shape(0);
    a.nP = nP.data();
    a.frame = frame.data();
    a.c = c.data();
    a.dP = dP;
    a.radius = radius;
    a.atol = atol;
    const auto num = [&](const char* k) { return tol[k].cast<double>(); };
    const auto whole = [&](const char* k) { return tol[k].cast<std::int64_t>(); };
    a.hull_rtol = num("AREA_HULL_RTOL");
    a.event_parallel = num("AREA_EVENT_PARALLEL");
    a.extend_rtol = num("AREA_CUT_EXTEND_RTOL");
    a.curve_rtol = num("AREA_CURVED_EVENT_RTOL");
    a.samples = whole("AREA_CURVED_EVENT_SAMPLES");
    a.bisections = whole("AREA_CURVED_EVENT_BISECTIONS");
    a.max_triples = whole("AREA_CURVED_MAX_TRIPLES");
    a.chord_split = num("AREA_CURVED_CHORD_SPLIT");
    a.chord_halvings = whole("AREA_CURVED_CHORD_HALVINGS");
    a.rows_per_call = whole("AREA_EVENT_ROWS_PER_CALL");
    if (a.samples < 1) throw std::invalid_argument("curved_event_lines: samples < 1");
    exactff::CurvedResult r;
    {
        py::gil_scoped_release release;
        r = exactff::curved_event_lines(a);
    }
    py::array_t<double> seg = as_array(r.segments);
    return py::make_tuple(seg.reshape({py::ssize_t(r.segments.size() / 4), py::ssize_t(2),
                                       py::ssize_t(2)}),
                          r.events, r.skipped);
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
                          as_array(r.areas), r.lines, r.ok);
}

exactff::TriangleRule as_rule(py::handle r) {
    // a collapsed rule as (nodes, weights) on [-1, 1]; a symmetric one as (B (m, 3), w (m,))
    auto t = r.cast<py::tuple>();
    Array<double> x = t[0].cast<Array<double>>(), w = t[1].cast<Array<double>>();
    exactff::TriangleRule out;
    out.collapsed = x.ndim() == 1;
    out.x = exactff::bind::to_vector(x);
    out.w = exactff::bind::to_vector(w);
    if ((out.collapsed && out.x.size() != out.w.size()) ||
        (!out.collapsed && out.x.size() != 3 * out.w.size()))
        throw std::invalid_argument("adaptive_levels: a rule of the wrong shape");
    return out;
}

// the null rules (the last two) weigh the nodes of the symmetric pair (the first two)
void check_null_rules(const exactff::TriangleRule* rule) {
    const size_t nodes = rule[0].w.size() + rule[1].w.size();
    if (rule[0].collapsed || rule[1].collapsed || rule[9].w.size() != nodes ||
        rule[10].w.size() != nodes)
        throw std::invalid_argument("adaptive_levels: null rules not on the symmetric pair");
}

py::tuple adaptive_levels(Array<double> T, Array<long long> depth, Array<long long> rung,
                          Array<bool> corner, Array<double> nP, Array<double> frame,
                          double area_P, double total_area, double atol, double rules_err,
                          long long start, py::sequence rules, bool symmetric, Array<double> Qc,
                          Array<double> corners, Array<double> q0, Array<double> nQ,
                          Array<double> RQ, Array<double> blockers, Array<long long> counts,
                          Array<double> normals, Array<long long> groups, double extent,
                          Array<double> parts, Array<long long> part_counts, Array<double> lo,
                          Array<double> hi, py::dict tol) {
    const std::int64_t t = T.size() / 9;
    if (T.size() != 9 * t || depth.size() != t || rung.size() != t || corner.size() != t ||
        nP.size() != 3 || frame.size() != 9 || Qc.ndim() != 2 || Qc.shape(1) != 3 ||
        Qc.shape(0) < 3 || lo.size() != 3 || hi.size() != 3 ||
        py::len(rules) != exactff::kLevelRules)
        throw std::invalid_argument("adaptive_levels: arrays of the wrong shapes");
    for (std::int64_t k = 0; k < t; ++k)
        if (rung.data()[k] != 0 && rung.data()[k] != 1)
            throw std::invalid_argument("adaptive_levels: a rung not 0 or 1");
    std::vector<exactff::TriangleRule> rule(exactff::kLevelRules);
    for (int k = 0; k < exactff::kLevelRules; ++k) rule[k] = as_rule(rules[k]);
    check_null_rules(rule.data());
    exactff::LevelArgs a;
    a.T = exactff::bind::to_vector(T);
    a.depth = exactff::bind::to_vector(depth);
    a.rung = exactff::bind::to_vector(rung);
    a.corner.assign(corner.data(), corner.data() + t);
    a.nP = nP.data();
    a.frame = frame.data();
    a.area_P = area_P;
    a.total_area = total_area;
    a.atol = atol;
    a.rules_err = rules_err;
    a.start = start;
    for (int k = 0; k < exactff::kLevelRules; ++k) a.rules[k] = &rule[k];
    a.symmetric = symmetric;
    a.Qc = Qc.data();
    a.n_q = Qc.shape(0);
    exactff::HiddenArgs& h = a.hidden;
    exactff::bind::set_hidden_geometry(h, "adaptive_levels", corners, q0, nQ, RQ, blockers,
                                       counts, normals, groups, parts, part_counts, frame,
                                       extent);
    const auto num = [&](const char* k) { return tol[k].cast<double>(); };
    h.vertex_ulps = num("AREA_IMAGE_ULPS");
    h.sliver_ulps = num("AREA_SLIVER_ULPS");
    h.max_pieces = tol["AREA_MAX_PIECES"].cast<long long>();
    h.precise_rtol = num("AREA_IMAGE_PRECISE_RTOL");
    h.c1 = num("C1");
    h.c2 = num("C2");
    h.eps = num("EPS");
    a.lo = lo.data();
    a.hi = hi.data();
    long long lines = 1 + corners.shape(0);
    for (std::int64_t k = 0; k < counts.size(); ++k) lines += counts.data()[k];
    for (std::int64_t k = 0; k < part_counts.size(); ++k) lines += part_counts.data()[k];
    a.lines = static_cast<double>(lines);
    a.sliver_share = num("AREA_SLIVER_SHARE");
    a.small_share = num("AREA_SMALL_TRIANGLE_SHARE");
    a.small_reach = num("AREA_SMALL_TRIANGLE_REACH");
    a.null_factor = num("AREA_NULL_RULE_FACTOR");
    a.budget_share = num("AREA_IMAGE_BUDGET_SHARE");
    a.back_face_rtol = num("AREA_BACK_FACE_RTOL");
    a.edge_on_rtol = num("AREA_EDGE_ON_RTOL");
    a.precise_share = num("AREA_IMAGE_PRECISE_SHARE");
    a.boolean_ulps = num("AREA_BOOLEAN_ULPS");
    a.image_rtol = num("AREA_IMAGE_RTOL");
    a.eps = num("EPS");
    a.c1 = num("C1");
    a.c2 = num("C2");
    a.offset_ulps = num("OFFSET_ROUNDING_ULPS");
    a.max_depth = tol["AREA_MAX_DEPTH"].cast<long long>();
    a.points_per_call = tol["AREA_POINTS_PER_CALL"].cast<long long>();
    if (a.points_per_call < 1) throw std::invalid_argument("adaptive_levels: points_per_call < 1");
    exactff::LevelResult r;
    {
        py::gil_scoped_release release;
        r = exactff::adaptive_levels(a);
    }
    if (!r.ok) return py::make_tuple(false);
    py::array_t<bool> cn(py::ssize_t(r.corner.size()));
    std::copy(r.corner.begin(), r.corner.end(), cn.mutable_data());
    py::array_t<double> tri = as_array(r.T);
    return py::make_tuple(true, tri.reshape({py::ssize_t(r.T.size() / 9), py::ssize_t(3),
                                             py::ssize_t(3)}),
                          as_array(r.depth), as_array(r.rung), cn, as_array(r.hi),
                          as_array(r.lo), as_array(r.diff), as_array(r.rnd), as_array(r.hiU),
                          as_array(r.loU), as_array(r.rndU), r.slivers, r.points,
                          r.back_faces);
}

std::shared_ptr<exactff::PairConstants> pair_constants(py::dict tol, py::sequence rules,
                                                        py::sequence fused) {
    if (py::len(rules) != exactff::kLevelRules)
        throw std::invalid_argument("pair_constants: 11 rules expected (levels.h)");
    auto k = std::make_shared<exactff::PairConstants>();
    const auto num = [&](const char* name) { return tol[name].cast<double>(); };
    const auto whole = [&](const char* name) { return tol[name].cast<long long>(); };
    k->hidden_pad = num("AREA_HIDDEN_PAD");
    k->ray_parallel = num("AREA_RAY_PARALLEL");
    k->event_parallel = num("AREA_EVENT_PARALLEL");
    k->event_line_ulps = num("AREA_EVENT_LINE_ULPS");
    k->hull_rtol = num("AREA_HULL_RTOL");
    k->extend_rtol = num("AREA_CUT_EXTEND_RTOL");
    k->curve_rtol = num("AREA_CURVED_EVENT_RTOL");
    k->chord_split = num("AREA_CURVED_CHORD_SPLIT");
    k->event_line_key = num("AREA_EVENT_LINE_KEY");
    k->sliver_cell = num("AREA_SLIVER_CELL");
    k->cell_cover_rtol = num("AREA_CELL_COVER_RTOL");
    k->cell_cover_atol_share = num("AREA_CELL_COVER_ATOL_SHARE");
    k->low_rules_tolerance = num("AREA_LOW_RULES_TOLERANCE");
    k->coplanar_ulps = num("BSP_COPLANAR_ULPS");
    k->eps = num("EPS");
    k->bound_cos_slack = num("AREA_BOUND_COS_SLACK");
    k->bound_spread_ulps = num("AREA_BOUND_SPREAD_ULPS");
    k->unevaluated_share = num("AREA_UNEVALUATED_SHARE");
    k->unevaluated_least = num("AREA_UNEVALUATED_LEAST");
    k->samples = whole("AREA_CURVED_EVENT_SAMPLES");
    k->bisections = whole("AREA_CURVED_EVENT_BISECTIONS");
    k->max_triples = whole("AREA_CURVED_MAX_TRIPLES");
    k->chord_halvings = whole("AREA_CURVED_CHORD_HALVINGS");
    k->rows_per_call = whole("AREA_EVENT_ROWS_PER_CALL");
    k->umbra_min_lines = whole("AREA_UMBRA_MIN_LINES");
    k->max_event_lines = whole("AREA_MAX_EVENT_LINES");
    k->many_cells = whole("AREA_MANY_CELLS");
    k->convex_ulps = num("CONVEX_TURN_ULPS");
    k->meet_ulps = num("CLIP_MEET_ULPS");
    k->normal_floor = num("NORMAL_FLOOR");
    k->strict_turn = num("AREA_STRICT_TURN");
    k->vertex_ulps = num("AREA_IMAGE_ULPS");
    k->sliver_ulps = num("AREA_SLIVER_ULPS");
    k->precise_rtol = num("AREA_IMAGE_PRECISE_RTOL");
    k->c1 = num("C1");
    k->c2 = num("C2");
    k->sliver_share = num("AREA_SLIVER_SHARE");
    k->small_share = num("AREA_SMALL_TRIANGLE_SHARE");
    k->small_reach = num("AREA_SMALL_TRIANGLE_REACH");
    k->null_factor = num("AREA_NULL_RULE_FACTOR");
    k->budget_share = num("AREA_IMAGE_BUDGET_SHARE");
    k->back_face_rtol = num("AREA_BACK_FACE_RTOL");
    k->edge_on_rtol = num("AREA_EDGE_ON_RTOL");
    k->precise_share = num("AREA_IMAGE_PRECISE_SHARE");
    k->boolean_ulps = num("AREA_BOOLEAN_ULPS");
    k->image_rtol = num("AREA_IMAGE_RTOL");
    k->offset_ulps = num("OFFSET_ROUNDING_ULPS");
    k->max_pieces = whole("AREA_MAX_PIECES");
    k->max_depth = whole("AREA_MAX_DEPTH");
    k->points_per_call = whole("AREA_POINTS_PER_CALL");
    if (k->samples < 1 || k->points_per_call < 1)
        throw std::invalid_argument("pair_constants: samples or points_per_call < 1");
    for (int r = 0; r < exactff::kLevelRules; ++r) k->rules[r] = as_rule(rules[r]);
    check_null_rules(k->rules);
    if (py::len(fused) != 3) throw std::invalid_argument("pair_constants: 3 flags in fused");
    k->fused_dot = fused[0].cast<bool>();
    k->fused_matmul = fused[1].cast<bool>();
    k->fused_stacked = fused[2].cast<bool>();
    return k;
}

py::tuple occluded_pair(Array<double> W, Array<std::int64_t> start, Array<std::int64_t> solid,
                        Array<double> inner, Array<double> Pc, Array<double> Qc,
                        Array<double> nP, double atol, double area_P, double whole_value,
                        double whole_err, bool shortcuts,
                        std::shared_ptr<exactff::PairConstants> constants) {
    const std::int64_t n = start.size() - 1;
    if (W.ndim() != 2 || W.shape(1) != 3 || n < 2 || nP.size() != 3 || Pc.ndim() != 2 ||
        Pc.shape(1) != 3 || Pc.shape(0) < 3 || Qc.ndim() != 2 || Qc.shape(1) != 3 ||
        Qc.shape(0) < 3 || (solid.size() != 0 && solid.size() != n) ||
        (inner.size() != 0 && inner.size() != 3 * n) || !constants)
        throw std::invalid_argument("occluded_pair: arrays of the wrong shapes");
    check_polygon_starts(start, W.shape(0), "occluded_pair");
    exactff::PairArgs a;
    a.W = W.data();
    a.start = start.data();
    a.n = n;
    a.solid = solid.size() ? solid.data() : nullptr;
    a.inner = inner.size() ? inner.data() : nullptr;
    a.Pc = Pc.data();
    a.n_p = Pc.shape(0);
    a.Qc = Qc.data();
    a.n_q = Qc.shape(0);
    a.nP = nP.data();
    a.atol = atol;
    a.area_P = area_P;
    a.whole_value = whole_value;
    a.whole_err = whole_err;
    a.shortcuts = shortcuts;
    a.k = constants.get();
    exactff::PairResult r;
    {
        py::gil_scoped_release release;
        r = exactff::occluded_pair(a);
    }
    return py::make_tuple(r.status, r.value, r.err, r.points, r.culled_events, r.solid_events,
                          r.curved_events, r.curved_skipped, r.back_faces, r.unevaluated);
}

py::tuple corner_first(Array<double> T, Array<double> Vb, Array<double> n, double dP,
                       double reach, double hull_rtol) {
    if (T.size() % 9 || (Vb.size() && (Vb.ndim() != 2 || Vb.shape(1) != 3)) || n.size() != 3)
        throw std::invalid_argument("corner_first: T (t, 3, 3), Vb (m, 3), n (3,) expected");
    std::vector<double> tri = exactff::bind::to_vector(T);
    std::vector<unsigned char> corner;
    {
        py::gil_scoped_release release;
        exactff::corner_first(tri, Vb.data(), Vb.size() / 3, n.data(), dP, reach, hull_rtol,
                              corner);
    }
    py::array_t<bool> c(py::ssize_t(corner.size()));
    std::copy(corner.begin(), corner.end(), c.mutable_data());
    py::array_t<double> out = as_array(tri);
    return py::make_tuple(out.reshape({py::ssize_t(tri.size() / 9), py::ssize_t(3), py::ssize_t(3)}),
                          c);
}

py::tuple hidden_setup(Array<double> Qc, Array<double> W, Array<std::int64_t> start,
                       Array<std::int64_t> solid, Array<double> inner, py::dict tol) {
    const std::int64_t n = start.size() - 1;
    if (Qc.ndim() != 2 || Qc.shape(1) != 3 || Qc.shape(0) < 3 || W.ndim() != 2 ||
        W.shape(1) != 3 || n < 0 || (solid.size() != 0 && solid.size() != n) ||
        inner.size() != 3 * solid.size())
        throw std::invalid_argument("hidden_setup: arrays of the wrong shapes");
    check_polygon_starts(start, W.shape(0), "hidden_setup");
    const std::int64_t* s = start.data();
    exactff::SetupArgs a;
    a.Qc = Qc.data();
    a.n_q = Qc.shape(0);
    a.W = W.data();
    a.start = s;
    a.n = n;
    a.solid = solid.size() ? solid.data() : nullptr;
    a.inner = solid.size() ? inner.data() : nullptr;
    const auto num = [&](const char* k) { return tol[k].cast<double>(); };
    a.eps = num("EPS");
    a.convex_ulps = num("CONVEX_TURN_ULPS");
    a.meet_ulps = num("CLIP_MEET_ULPS");
    a.normal_floor = num("NORMAL_FLOOR");
    a.strict_turn = num("AREA_STRICT_TURN");
    a.hull_rtol = num("AREA_HULL_RTOL");
    exactff::SetupResult r;
    {
        py::gil_scoped_release release;
        r = exactff::hidden_setup(a);
    }
    if (r.status) return py::make_tuple(r.status);
    const auto vec = [](const double* p, py::ssize_t k) {
        return as_array(std::vector<double>(p, p + k));
    };
    py::array_t<double> V = as_array(r.V);
    return py::make_tuple(0, vec(r.nQ, 3), vec(r.q0, 3), vec(r.RQ, 9).reshape({3, 3}),
                          V.reshape({py::ssize_t(r.counts.size()), py::ssize_t(r.stride),
                                     py::ssize_t(3)}),
                          as_array(r.counts), as_array(r.NK, 3), as_array(r.group),
                          as_array(r.kept), vec(r.lo, 3), vec(r.hi, 3), r.extent);
}

}  // namespace

PYBIND11_MODULE(_pair, m) {
    m.doc() = "An occluded pair of an area row, compiled (exactff.area).";
    py::class_<exactff::PairConstants, std::shared_ptr<exactff::PairConstants>>(
        m, "PairConstants", "The tolerances and rules occluded_pair reads (occluded_pair.h).");
    m.def("pair_constants", &pair_constants, py::arg("tol"), py::arg("rules"), py::arg("fused"),
          "pair_constants(tol, rules, fused) -> PairConstants: the tolerances by name, the "
          "levels' eleven rules and whether numpy's BLAS fuses the multiply-adds of a dot, a "
          "matrix and a stacked product (numpy_ops.h), for occluded_pair");
    m.def("occluded_pair", &occluded_pair, py::arg("W"), py::arg("start"), py::arg("solid"),
          py::arg("inner"), py::arg("Pc"), py::arg("Qc"), py::arg("nP"), py::arg("atol"),
          py::arg("area_P"), py::arg("whole_value"), py::arg("whole_err"),
          py::arg("shortcuts"), py::arg("constants"),
          "occluded_pair(...) -> (status, value, err, points, culled_events, solid_events, "
          "curved_events, curved_skipped, back_faces, unevaluated): adaptive.py's "
          "_hidden_integral in one "
          "call, status 0, or declined (status > 0, the rest 0; occluded_pair.h)");
    m.def("event_lines", &event_lines, py::arg("W"), py::arg("start"), py::arg("solid"),
          py::arg("nP"), py::arg("dP"), py::arg("frame"), py::arg("c"), py::arg("radius"),
          py::arg("nQ"), py::arg("q0"), py::arg("RQ"), py::arg("Q2"), py::arg("shortcuts"),
          py::arg("ray_parallel"), py::arg("event_parallel"), py::arg("line_ulps"),
          py::arg("eps"),
          "event_lines(...) -> (segments (m, 2, 2), culled_events, solid_events): the pair's "
          "vertex-edge events as segments of the emitter's plane (pair.h)");
    m.def("curved_event_lines", &curved_event_lines, py::arg("W"), py::arg("start"),
          py::arg("solid"), py::arg("Qc"), py::arg("nP"), py::arg("dP"), py::arg("frame"),
          py::arg("c"), py::arg("radius"), py::arg("atol"), py::arg("tol"),
          "curved_event_lines(...) -> (segments (m, 2, 2), curved_events, skipped): the pair's "
          "curved events traced as chords of the emitter's plane (pair.h)");
    m.def("cut_cells", &cut_cells, py::arg("P2"), py::arg("segments"), py::arg("step"),
          py::arg("merge"), py::arg("sliver"),
          "cut_cells(P2, segments, step, merge, sliver) -> (triangles (t, 3, 2), areas, lines, ok): "
          "the emitter cut along the event lines, collinear ones joined (pair.h)");
    m.def("adaptive_levels", &adaptive_levels, py::arg("T"), py::arg("depth"), py::arg("rung"),
          py::arg("corner"), py::arg("nP"), py::arg("frame"), py::arg("area_P"),
          py::arg("total_area"), py::arg("atol"), py::arg("rules_err"), py::arg("start"),
          py::arg("rules"), py::arg("symmetric"), py::arg("Qc"), py::arg("corners"),
          py::arg("q0"), py::arg("nQ"), py::arg("RQ"), py::arg("blockers"), py::arg("counts"),
          py::arg("normals"), py::arg("groups"), py::arg("extent"), py::arg("parts"),
          py::arg("part_counts"), py::arg("lo"), py::arg("hi"), py::arg("tol"),
          "adaptive_levels(...) -> (True, T, depth, rung, corner, hi, lo, diff, rnd, hiU, "
          "loU, rndU, slivers, points, back_faces) or (False,): the adaptive levels of an "
          "occluded pair's hidden part (levels.h)");
    m.def("corner_first", &corner_first, py::arg("T"), py::arg("Vb"), py::arg("n"), py::arg("dP"),
          py::arg("reach"), py::arg("hull_rtol"),
          "corner_first(T, Vb, n, dP, reach, hull_rtol) -> (T, corner): the cells' triangles, "
          "each with first a vertex a blocker touches (levels.h)");
    m.def("hidden_setup", &hidden_setup, py::arg("Qc"), py::arg("W"), py::arg("start"),
          py::arg("solid"), py::arg("inner"), py::arg("tol"),
          "hidden_setup(Qc, W, start, solid, inner, tol) -> (0, nQ, q0, RQ, V, counts, NK, "
          "group, kept, lo, hi, extent), (1,): no blocker in front, or (2,): declined "
          "(hidden_setup.h)");
}
