// The compiled z-buffer of the discrete methods (issue 55): scan conversion of
// polygons already clipped and projected onto a method's planar face, and the depth
// buffer, one row at a time.
//
// It does what the numpy rasteriser does (exactff/methods/_raster.py,
// rasterise_face, and exactff/methods/_sampling.py, resolve_depths), cell for cell,
// so that the numpy code stays its test oracle:
//
// - scanlines at the face's row centres within each polygon's extent; an edge
//   crosses a scanline y when exactly one end point is above it ("at or below" to
//   "above"), and the crossing is evaluated from the edge's lower end point,
//   x = a_x + (y - a_y) (c_x - a_x) / (c_y - a_y), so that an edge shared by two
//   polygons gives the same crossing in both; crossings sorted, spans [x1, x2),
//   [x3, x4), ... of cell centres (even-odd rule);
// - the depth along a cell's direction d, t = n . (c - p) / (n . d); of the polygons
//   at the nearest depth and those tied with them (coplanar by the BSP tree's rule,
//   exactff.predicates.coplanar_pairs), the one of lowest tie priority
//   (exactff.predicates.tie_priority);
// - candidates are resolved in the same chunks as the numpy code (PAIR_CHUNK
//   polygon-scanline pairs, DEPTH_CHUNK candidates), with the same rule inside a
//   chunk and across chunks, so that even a depth tie that is not transitive (three
//   polygons, two pairs coplanar) resolves identically;
// - every floating-point expression in the numpy order (numpy's einsum over three
//   components adds the first and third products, then the second).
//
// The work runs without the GIL.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace {

using i64 = std::int64_t;
// the arrays the functions take: C-ordered, converted from any dtype (except the depth
// buffer, which must be written in place)
using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Ints = py::array_t<i64, py::array::c_style | py::array::forcecast>;
using Bools = py::array_t<bool, py::array::c_style | py::array::forcecast>;
constexpr double INF = std::numeric_limits<double>::infinity();
// unit roundoff (exactff._tolerances.EPS)
constexpr double EPS = 1.1102230246251565e-16;

// numpy's einsum("ij,ij->i") over three components: (x0 y0 + x2 y2) + x1 y1
inline double dot3(const double* a, const double* b) {
    return (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1];
}

inline double absdot3(const double* a, const double* b) {
    return (std::fabs(a[0]) * std::fabs(b[0]) + std::fabs(a[2]) * std::fabs(b[2]))
           + std::fabs(a[1]) * std::fabs(b[1]);
}

// the depth buffer's per-cell scratch within a chunk (the nearest depth apart: the
// candidates touch it, the other fields only the chunk's resolution)
struct CellScratch {
    std::int64_t near = -1;                              // a polygon at the nearest depth
    std::int64_t p_min = std::numeric_limits<std::int64_t>::max();   // the lowest priority tied
    std::int64_t pick = -1;                              // its polygon
};

// one scratch per thread, grown as needed and reset cell by cell after every chunk
// (a row's buffer of 200,000 cells is not allocated and cleared again row by row):
// the fields above, the nearest depth per cell (INF: no candidate yet), and room for
// the list of the cells the chunk touched
struct Scratch {
    std::vector<CellScratch> cell;
    std::vector<double> t_min;
    std::vector<std::int64_t> touched;
};

Scratch& scratch(std::int64_t n_cells) {
    thread_local Scratch sc;
    if (static_cast<std::int64_t>(sc.cell.size()) < n_cells) {
        sc.cell.resize(static_cast<size_t>(n_cells));
        sc.t_min.resize(static_cast<size_t>(n_cells), INF);
        // (one more: a candidate writes its cell before counting it)
        sc.touched.resize(static_cast<size_t>(n_cells) + 1);
    }
    return sc;
}

// a candidate (cell, live polygon) of the current chunk: its depth and n . d
struct Candidate {
    double t, den;
    std::int32_t cell, s;    // (24 bytes: the chunk's candidates are the buffer's traffic)
};

class ZBuffer {
  public:
    // D (C, 3) cell directions, Dnorm (C,) their norms (np.linalg.norm, passed in so
    // that they are numpy's); nl (L, 3), dl (L,), band (L,), prio (L,) the live
    // polygons' depth data (ZBufferRow); V, offsets, N, Dp, ids the scene's polygons
    // and planes and the live polygons' scene indices (the coplanar rule);
    // coplanar_ulps: exactff._tolerances.BSP_COPLANAR_ULPS; tie_slack_ulps:
    // ZBUFFER_ROUNDING_ULPS + 1; clip_meet_ulps, chart_edge_ulps: CLIP_MEET_ULPS and
    // CHART_EDGE_ULPS (the chart clipper's).
    ZBuffer(Doubles D, Doubles Dnorm, Doubles nl, Doubles dl, Doubles band, Ints prio,
            Doubles V, Ints offsets, Doubles N, Doubles Dp, Ints ids,
            double coplanar_ulps, double tie_slack_ulps, double clip_meet_ulps,
            double chart_edge_ulps)
        : D_(D), Dnorm_(Dnorm), nl_(nl), dl_(dl), band_(band), prio_(prio), V_(V),
          offsets_(offsets), N_(N), Dp_(Dp), ids_(ids), coplanar_ulps_(coplanar_ulps),
          tie_slack_ulps_(tie_slack_ulps), clip_meet_ulps_(clip_meet_ulps),
          chart_edge_ulps_(chart_edge_ulps) {
        if (D.ndim() != 2 || D.shape(1) != 3)
            throw std::invalid_argument("D must have shape (C, 3)");
        n_cells_ = D.shape(0);
        n_live_ = dl.shape(0);
        if (n_cells_ >= (i64(1) << 31) || n_live_ >= (i64(1) << 31))
            throw std::invalid_argument("at most 2**31 - 1 cells and live polygons");
        D_p_ = D_.data();
        nl_p_ = nl_.data();
        dl_p_ = dl_.data();
        if (Dnorm.shape(0) != n_cells_)
            throw std::invalid_argument("Dnorm must have shape (C,)");
        if (nl.ndim() != 2 || nl.shape(0) != n_live_ || nl.shape(1) != 3 ||
            band.shape(0) != n_live_ || prio.shape(0) != n_live_ || ids.shape(0) != n_live_)
            throw std::invalid_argument("nl, dl, band, prio, ids: one row per live polygon");
        if (V.ndim() != 2 || V.shape(1) != 3 || N.ndim() != 2 || N.shape(1) != 3 ||
            offsets.shape(0) != N.shape(0) + 1 || Dp.shape(0) != N.shape(0))
            throw std::invalid_argument("V, offsets, N, Dp: the scene's polygons and planes");
    }

    // Scan-convert M polygons on a face and depth-test them into (best_t, best).
    // UV (M, K, 2): face coordinates, padded by repeating the last vertex; scanlines
    // along UV[..., 0] at centres uc, spans along UV[..., 1] over centres vc;
    // cl (M,) vertex counts; src (M,) live indices; table (len(uc), len(vc)) the
    // layout's cell of each grid cell (-1: none).
    void face(Doubles UV, Ints cl, Ints src, Doubles uc, Doubles vc, Ints table,
              py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        if (UV.ndim() != 3 || UV.shape(2) != 2)
            throw std::invalid_argument("UV must have shape (M, K, 2)");
        const i64 M = UV.shape(0), K = UV.shape(1);
        if (cl.shape(0) != M || src.shape(0) != M)
            throw std::invalid_argument("cl and src must have shape (M,)");
        const i64 nu = uc.shape(0), nv = vc.shape(0);
        check_table(table, nu, nv);
        check_buffer(best_t, best);
        const double* uv = UV.data();
        const i64* c = cl.data();
        const i64* s = src.data();
        const double* u = uc.data();
        const double* v = vc.data();
        const i64* tab = table.data();
        double* bt = static_cast<double*>(best_t.mutable_data());
        i64* bs = static_cast<i64*>(best.mutable_data());
        for (i64 m = 0; m < M; ++m) {
            if (s[m] < 0 || s[m] >= n_live_)
                throw std::invalid_argument("src out of range");
            if (c[m] > K) throw std::invalid_argument("cl exceeds K");
        }
        py::gil_scoped_release release;
        scan(uv, M, K, c, s, nullptr, u, nu, v, nv, tab, bt, bs, pair_chunk, depth_chunk);
    }

    // The same for one bucket of polygons (local frame) clipped to a chart's frustum
    // first, as exactff.visibility.charts.chart_clip does (clip_chart below): V (M, K,
    // 3) padded vertices, counts (M,), g_ids (M,) their live indices, the chart's
    // frustum planes (4, 3) and axes.
    void chart_face(Doubles V, Ints counts, Ints g_ids, Doubles planes, Doubles eu, Doubles ev,
                    Doubles ew, bool side, Doubles uc, Doubles vc, Ints table,
                    py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        const i64 M = check_bucket(V, counts, planes, eu, ev, ew);
        if (g_ids.shape(0) != M) throw std::invalid_argument("g_ids must have shape (M,)");
        const i64 nu = uc.shape(0), nv = vc.shape(0);
        check_table(table, nu, nv);
        check_buffer(best_t, best);
        for (i64 m = 0; m < M; ++m)
            if (g_ids.data()[m] < 0 || g_ids.data()[m] >= n_live_)
                throw std::invalid_argument("g_ids out of range");
        double* bt = static_cast<double*>(best_t.mutable_data());
        i64* bs = static_cast<i64*>(best.mutable_data());
        py::gil_scoped_release release;
        Clipped c;
        clip_chart(V.data(), M, V.shape(1), counts.data(), planes.data(), eu.data(), ev.data(),
                   ew.data(), side, clip_meet_ulps_, chart_edge_ulps_, c);
        scan(c.UV.data(), static_cast<i64>(c.live.size()), c.K, c.cl.data(), g_ids.data(),
             c.live.data(), uc.data(), nu, vc.data(), nv, table.data(), bt, bs, pair_chunk,
             depth_chunk);
    }

    // Depth-test candidate (cell, live polygon) pairs, in chunks of depth_chunk.
    void candidates(Ints cell, Ints src, py::array best_t, py::array best, i64 depth_chunk) {
        check_buffer(best_t, best);
        const i64 n = cell.shape(0);
        if (src.shape(0) != n) throw std::invalid_argument("cell and src differ in length");
        const i64* c = cell.data();
        const i64* s = src.data();
        for (i64 k = 0; k < n; ++k)
            if (c[k] < 0 || c[k] >= n_cells_ || s[k] < 0 || s[k] >= n_live_)
                throw std::invalid_argument("cell or src out of range");
        double* bt = static_cast<double*>(best_t.mutable_data());
        i64* bs = static_cast<i64*>(best.mutable_data());
        py::gil_scoped_release release;
        use_scratch();
        for (i64 k = 0; k < n; ++k) add(c[k], s[k], bt, bs, depth_chunk);
        flush(bt, bs);
    }

    // exactff.visibility.charts.chart_clip (margin 0) of one bucket: (live, UV, cl)
    static py::tuple chart_clip(Doubles V, Ints counts, Doubles planes, Doubles eu, Doubles ev,
                                Doubles ew,
                                bool side, double clip_meet_ulps, double chart_edge_ulps) {
        const i64 M = check_bucket(V, counts, planes, eu, ev, ew);
        Clipped c;
        {
            py::gil_scoped_release release;
            clip_chart(V.data(), M, V.shape(1), counts.data(), planes.data(), eu.data(),
                       ev.data(), ew.data(), side, clip_meet_ulps, chart_edge_ulps, c);
        }
        return clipped_tuple(c);
    }

    // whether live polygons a[k] and b[k] are coplanar (the BSP tree's rule)
    py::array_t<bool> coplanar_many(Ints a, Ints b) {
        const i64 n = a.shape(0);
        py::array_t<bool> out(n);
        bool* o = out.mutable_data();
        for (i64 k = 0; k < n; ++k) o[k] = coplanar(a.data()[k], b.data()[k]);
        return out;
    }

    // The same for one bucket of polygons (local frame) clipped by a face's frustum
    // first, as exactff.methods._raster.FaceClip does (clip_face below): R (3, 3) the
    // face's frame (rows), planes (P, 3) the frustum in that frame (entries 0 and +-1),
    // scale the face coordinates' factor.
    void clipped_face(Doubles V, Ints counts, Ints g_ids, Doubles R, Doubles planes,
                      double scale, Doubles uc, Doubles vc, Ints table,
                      py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        const i64 M = check_face_bucket(V, counts, R, planes);
        check_ids(g_ids, M);
        const i64 nu = uc.shape(0), nv = vc.shape(0);
        check_table(table, nu, nv);
        const auto [bt, bs] = writable(best_t, best);
        py::gil_scoped_release release;
        Clipped c;
        clip_face(V.data(), M, V.shape(1), counts.data(), R.data(), planes.data(),
                  planes.shape(0), scale, clip_meet_ulps_, c);
        scan(c.UV.data(), static_cast<i64>(c.live.size()), c.K, c.cl.data(), g_ids.data(),
             c.live.data(), uc.data(), nu, vc.data(), nv, table.data(), bt, bs, pair_chunk,
             depth_chunk);
    }

    // exactff.methods._raster.FaceClip of one bucket, compiled: (live, UV, cl)
    static py::tuple face_clip(Doubles V, Ints counts, Doubles R, Doubles planes,
                               double scale, double clip_meet_ulps) {
        const i64 M = check_face_bucket(V, counts, R, planes);
        Clipped c;
        {
            py::gil_scoped_release release;
            clip_face(V.data(), M, V.shape(1), counts.data(), R.data(), planes.data(),
                      planes.shape(0), scale, clip_meet_ulps, c);
        }
        return clipped_tuple(c);
    }

    // The polar plane (exactff.methods._raster.rasterise_polar): one bucket clipped as
    // clipped_face does, scanned along every sector's ray within each image's angular
    // extent; radii (rings,) and the sectors' cos and sin (S,): the cell of ring i and
    // sector k is i S + k.
    void polar(Doubles V, Ints counts, Ints g_ids, Doubles R, Doubles planes, double scale,
               Doubles radii, Doubles cosv, Doubles sinv,
               py::array best_t, py::array best, i64 pair_chunk, i64 depth_chunk) {
        const i64 M = check_face_bucket(V, counts, R, planes);
        check_ids(g_ids, M);
        const i64 S = cosv.shape(0), nr = radii.shape(0);
        if (sinv.shape(0) != S || S < 1) throw std::invalid_argument("cos and sin: one per sector");
        if (nr * S != n_cells_) throw std::invalid_argument("rings x sectors must be the cells");
        const auto [bt, bs] = writable(best_t, best);
        py::gil_scoped_release release;
        Clipped c;
        clip_face(V.data(), M, V.shape(1), counts.data(), R.data(), planes.data(),
                  planes.shape(0), scale, clip_meet_ulps_, c);
        scan_polar(c, g_ids.data(), radii.data(), nr, cosv.data(), sinv.data(), S, bt, bs,
                   pair_chunk, depth_chunk);
    }

    // Discrete PPBH (exactff.methods._raster.rasterise_disk): the disk's scan of one
    // bucket (local frame), the polygons that, clipped to the horizon, pass within
    // near_rel (relative) of the point left out: scanlines at xc along the local y,
    // spans along x over yc (the coordinates swapped, as rasterise_disk has them);
    // table (len(xc), len(yc)) the layout's cell of each grid cell (-1: outside the
    // disk). Returns the bucket's indices of the polygons near the point; when there
    // are some, it scans only if after_near (the rasteriser casts their rays one by
    // one first, then calls again).
    py::array_t<i64> disk(Doubles V, Ints counts, Ints g_ids, Doubles xc, Doubles yc,
                          Ints table, py::array best_t, py::array best, i64 pair_chunk,
                          i64 depth_chunk, double near_rel, bool after_near) {
        const i64 M = check_vertices(V, counts);
        check_ids(g_ids, M);
        const i64 nx = xc.shape(0), ny = yc.shape(0);
        check_table(table, nx, ny);
        const auto [bt, bs] = writable(best_t, best);
        std::vector<i64> near;
        {
            py::gil_scoped_release release;
            Horizon h;
            clip_horizon(V.data(), M, V.shape(1), counts.data(), clip_meet_ulps_, near_rel, h);
            for (size_t k = 0; k < h.live.size(); ++k)
                if (h.near[k]) near.push_back(h.live[k]);
            if (near.empty() || after_near)
                scan_disk(h, g_ids.data(), xc.data(), nx, yc.data(), ny, table.data(), bt, bs,
                          pair_chunk, depth_chunk);
        }
        py::array_t<i64> out(static_cast<i64>(near.size()));
        std::copy(near.begin(), near.end(), out.mutable_data());
        return out;
    }

    // The shared sampling core's z-buffer of one chart and bucket
    // (exactff.methods._sampling._zbuffer_chart) for any directions (Monte Carlo's
    // rays): the bucket clipped to the chart's exact frustum (chart_face's clipping),
    // each image's bounding box over the chart's grid of buckets of directions
    // (cells (n,) the directions' indices, cu, cv their chart coordinates, nb and
    // v_lo the grid, order and starts its CSR lists), the crossing number over the
    // image's edges, the depth buffer in chunks of pair_chunk (polygon, direction)
    // pairs. False (and nothing done) where the clipped images are wider than
    // long_polygon vertices: the numpy code tests those with shapely.
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
        const auto [bt, bs] = writable(best_t, best);
        py::gil_scoped_release release;
        Clipped c;
        clip_chart(V.data(), M, V.shape(1), counts.data(), planes.data(), eu.data(), ev.data(),
                   ew.data(), side, clip_meet_ulps_, chart_edge_ulps_, c);
        if (c.live.empty()) return true;
        if (c.K > long_polygon) return false;
        scan_rays(c, g_ids.data(), cells.data(), cu.data(), cv.data(), nb, v_lo, order.data(),
                  starts.data(), bt, bs, pair_chunk);
        return true;
    }

  private:
    // scan conversion of M polygons UV (M, K, 2) with counts c, live indices
    // src[pos[m]] (pos null: src[m]), into the depth buffer
    void scan(const double* uv, i64 M, i64 K, const i64* c, const i64* src, const i64* pos,
              const double* u, i64 nu, const double* v, i64 nv, const i64* tab, double* bt,
              i64* bs, i64 pair_chunk, i64 depth_chunk) {
        // the numpy code's chunks: (polygon, scanline) pairs by PAIR_CHUNK // K
        const i64 step = std::max<i64>(1, pair_chunk / std::max<i64>(K, 1));
        i64 pairs_in_chunk = 0;
        std::vector<double> X;
        X.reserve(static_cast<size_t>(K));
        use_scratch();
        for (i64 m = 0; m < M; ++m) {
            const double* P = uv + m * K * 2;
            const i64 n = c[m];
            const i64 sm = src[pos ? pos[m] : m];
            // the scanlines whose centre lies in [min y, max y] (none if a coordinate
            // is NaN, as numpy's min and searchsorted have it)
            double lo = INF, hi = -INF;
            bool nan = false;
            for (i64 e = 0; e < K; ++e) {
                const double y = P[2 * e];
                if (std::isnan(y)) nan = true;
                lo = std::min(lo, y);
                hi = std::max(hi, y);
            }
            if (nan) continue;
            const i64 j0 = std::lower_bound(u, u + nu, lo) - u;
            const i64 j1 = std::upper_bound(u, u + nu, hi) - u;
            for (i64 r = j0; r < j1; ++r) {
                const double y = u[r];
                X.clear();
                for (i64 e = 0; e < n; ++e) {
                    const double* a = P + 2 * e;
                    const double* b = P + 2 * ((e + 1) % n);
                    if ((a[0] > y) == (b[0] > y)) continue;
                    // from the lower end point, whichever way the edge runs
                    if (a[0] > b[0]) std::swap(a, b);
                    const double x = a[1] + (y - a[0]) * (b[1] - a[1]) / (b[0] - a[0]);
                    if (!std::isnan(x)) X.push_back(x);
                }
                std::sort(X.begin(), X.end());
                const size_t npairs = std::min<size_t>(X.size() / 2, static_cast<size_t>(K / 2));
                for (size_t k = 0; k < npairs; ++k) {
                    const i64 ia = std::lower_bound(v, v + nv, X[2 * k]) - v;
                    const i64 ib = std::lower_bound(v, v + nv, X[2 * k + 1]) - v;
                    for (i64 col = ia; col < ib; ++col) {
                        const i64 cell = tab[r * nv + col];
                        if (cell < 0) continue;
                        add(cell, sm, bt, bs, depth_chunk);
                    }
                }
                if (++pairs_in_chunk == step) {
                    flush(bt, bs);
                    pairs_in_chunk = 0;
                }
            }
        }
        flush(bt, bs);
    }


    // ---- the chart clipper: exactff.visibility.charts.chart_clip (margin 0) and
    // exactff.halfspace.clip_halfspace, expression for expression ----

    struct Clipped {
        std::vector<i64> live, cl;   // indices into the bucket, vertex counts
        std::vector<double> UV;      // (live, K, 2), padded by the last vertex
        i64 K = 0;
    };

    static i64 check_bucket(const Doubles& V,
                            const Ints& counts,
                            const Doubles& planes,
                            const Doubles& eu,
                            const Doubles& ev,
                            const Doubles& ew) {
        if (V.ndim() != 3 || V.shape(2) != 3)
            throw std::invalid_argument("V must have shape (M, K, 3)");
        const i64 M = V.shape(0);
        if (counts.shape(0) != M) throw std::invalid_argument("counts must have shape (M,)");
        for (i64 m = 0; m < M; ++m)
            if (counts.data()[m] > V.shape(1) || counts.data()[m] < 0)
                throw std::invalid_argument("counts out of range");
        if (planes.ndim() != 2 || planes.shape(0) != 4 || planes.shape(1) != 3)
            throw std::invalid_argument("planes must have shape (4, 3)");
        if (eu.size() != 3 || ev.size() != 3 || ew.size() != 3)
            throw std::invalid_argument("eu, ev, ew must have shape (3,)");
        return M;
    }

    // V @ h with h of the chart's axes (components 0, +-1): exact whatever the order
    static inline double hdot(const double* h, const double* x) {
        return (h[0] * x[0] + h[1] * x[1]) + h[2] * x[2];
    }

    static inline double sum_abs3(double a, double b, double c) {
        return (std::fabs(a) + std::fabs(b)) + std::fabs(c);
    }

    // clip_halfspace: polygons V (M, K, 3) with counts to h . x > 0; out (M, Kn, 3)
    static void clip_halfspace(const std::vector<double>& V, i64 M, i64 K,
                               const std::vector<i64>& counts, const double* h, const double C,
                               std::vector<double>& out, i64& Kn, std::vector<i64>& nc) {
        const double floor_ = std::numeric_limits<double>::min() / EPS;   // _NORMAL_FLOOR
        const double hsum = sum_abs3(h[0], h[1], h[2]);
        std::vector<double> tmp(static_cast<size_t>(M * 2 * K * 3));
        std::vector<double> s(static_cast<size_t>(K));
        nc.assign(static_cast<size_t>(M), 0);
        i64 kmax = 0;
        for (i64 m = 0; m < M; ++m) {
            const double* P = V.data() + m * K * 3;
            const i64 n = counts[m];
            for (i64 k = 0; k < K; ++k) s[k] = hdot(h, P + 3 * k);
            double* o = tmp.data() + m * 2 * K * 3;
            i64 w = 0;
            for (i64 k = 0; k < n; ++k) {
                const i64 j = (k + 1) % n;
                const bool in = s[k] > 0, in_n = s[j] > 0;
                if (in) {
                    for (int i = 0; i < 3; ++i) o[3 * w + i] = P[3 * k + i];
                    ++w;
                }
                if (in == in_n) continue;
                // the crossing from the inside end point: interpolated, or the meet of
                // the edge's plane through the origin with h where it is as good
                const double* A = in ? P + 3 * k : P + 3 * j;
                const double* B = in ? P + 3 * j : P + 3 * k;
                const double sa = in ? s[k] : s[j], sb = in ? s[j] : s[k];
                const double t = sa / (sa - sb);
                double X[3], e[3];
                for (int i = 0; i < 3; ++i) {
                    X[i] = A[i] + t * (B[i] - A[i]);
                    e[i] = B[i] - A[i];
                }
                const double d = sa - sb;
                const double mm[3] = {A[1] * e[2] - A[2] * e[1], A[2] * e[0] - A[0] * e[2],
                                      A[0] * e[1] - A[1] * e[0]};
                const double la = sum_abs3(A[0], A[1], A[2]), le = sum_abs3(e[0], e[1], e[2]);
                const double meet[3] = {(mm[1] * h[2] - mm[2] * h[1]) / d,
                                        (mm[2] * h[0] - mm[0] * h[2]) / d,
                                        (mm[0] * h[1] - mm[1] * h[0]) / d};
                const double cond = 1.0 + hsum * le / std::fabs(d);
                const bool use =
                    (sum_abs3(meet[0] - X[0], meet[1] - X[1], meet[2] - X[2]) <=
                     C * EPS * (la + le) * cond) &&
                    (cond * C * EPS < 1.0) &&
                    (sum_abs3(mm[0], mm[1], mm[2]) > C * EPS * la * le) &&
                    (std::fabs(d) > floor_) && (la * le > floor_);
                for (int i = 0; i < 3; ++i) o[3 * w + i] = use ? meet[i] + 0.0 : X[i];
                ++w;
            }
            nc[m] = w;
            kmax = std::max(kmax, w);
        }
        Kn = std::max<i64>(kmax, 1);
        out.assign(static_cast<size_t>(M * Kn * 3), 0.0);
        for (i64 m = 0; m < M; ++m)
            std::copy(tmp.data() + m * 2 * K * 3, tmp.data() + m * 2 * K * 3 + nc[m] * 3,
                      out.data() + m * Kn * 3);
    }

    // S polygons Vc (S, Kc, 3) with counts cc clipped plane after plane (planes
    // (n_planes, 3)), as chart_clip and FaceClip loop: each time the polygons with
    // fewer than 3 vertices left given count 0, and no more planes once none has 3;
    // Kc becomes the last clip's width
    static void clip_planes(std::vector<double>& Vc, i64 S, i64& Kc, std::vector<i64>& cc,
                            const double* planes, i64 n_planes, double meet_ulps) {
        std::vector<double> next;
        std::vector<i64> ncount;
        for (i64 j = 0; j < n_planes; ++j) {
            bool any = false;
            for (const i64 n : cc) any = any || n >= 3;
            if (!any) break;
            for (i64& n : cc) if (n < 3) n = 0;
            i64 Kn;
            clip_halfspace(Vc, S, Kc, cc, planes + 3 * j, meet_ulps, next, Kn, ncount);
            Vc.swap(next);
            cc.swap(ncount);
            Kc = Kn;
        }
    }

    // np.spacing(|x|): the gap to the next double (NaN for inf and NaN)
    static inline double spacing_abs(double x) {
        x = std::fabs(x);
        if (!std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
        return std::nextafter(x, INF) - x;
    }

    // charts.merge_close over the values x: near-coincident ones (each within
    // CHART_EDGE_ULPS ulps of the previous, sorted) replaced by the first of their run;
    // NaN sorts last and compares false, as numpy's unique and diff have it
    static void merge_close(std::vector<double>& x, double ulps) {
        std::vector<double> u(x);
        std::sort(u.begin(), u.end(), [](double a, double b) {
            if (std::isnan(a)) return false;
            if (std::isnan(b)) return true;
            return a < b;
        });
        // unique (NaNs collapsed)
        std::vector<double> q;
        for (const double a : u) {
            if (!q.empty() && (q.back() == a || (std::isnan(q.back()) && std::isnan(a)))) continue;
            q.push_back(a);
        }
        std::vector<double> first(q.size());
        for (size_t i = 0; i < q.size(); ++i) {
            const bool new_run = i == 0 || (q[i] - q[i - 1] > ulps * spacing_abs(q[i]));
            first[i] = new_run ? q[i] : first[i - 1];
        }
        for (double& a : x) {
            size_t i;
            if (std::isnan(a)) {
                i = q.size() - 1;
            } else {
                i = std::lower_bound(q.begin(), q.end(), a, [](double p, double v) {
                        return !std::isnan(p) && p < v;
                    }) - q.begin();
            }
            a = first[i];
        }
    }

    static void clip_chart(const double* V, i64 M, i64 K, const i64* counts,
                           const double* planes, const double* eu, const double* ev,
                           const double* ew, bool side, double meet_ulps, double edge_ulps,
                           Clipped& out) {
        // which polygons reach the frustum, which lie wholly inside it
        std::vector<i64> reach, straddle;
        std::vector<char> inside_all;
        for (i64 m = 0; m < M; ++m) {
            const double* P = V + m * K * 3;
            const i64 n = counts[m];
            bool outside = false, inside = true;
            for (int j = 0; j < 4; ++j) {
                bool all_out = true;
                for (i64 k = 0; k < n; ++k) {
                    const double sv = hdot(planes + 3 * j, P + 3 * k);
                    // (a NaN is neither out nor in, as numpy's comparisons have it)
                    if (!(sv <= 0)) all_out = false;
                    if (!(sv > 0)) inside = false;
                }
                if (all_out) outside = true;
            }
            if (!outside && n >= 3) {
                reach.push_back(m);
                inside_all.push_back(inside ? 1 : 0);
                if (!inside) straddle.push_back(m);
            }
        }
        // the straddling ones clipped plane by plane
        const i64 S = static_cast<i64>(straddle.size());
        std::vector<double> Vc(static_cast<size_t>(S * K * 3));
        std::vector<i64> cc(static_cast<size_t>(S));
        for (i64 i = 0; i < S; ++i) {
            std::copy(V + straddle[i] * K * 3, V + (straddle[i] + 1) * K * 3, Vc.data() + i * K * 3);
            cc[i] = counts[straddle[i]];
        }
        i64 Kc = K;
        clip_planes(Vc, S, Kc, cc, planes, 4, meet_ulps);
        const i64 Kr = std::max(K, Kc);
        // the live ones, padded by their last vertex, projected into the chart
        out.live.clear();
        out.cl.clear();
        out.K = Kr;
        std::vector<double> P3(static_cast<size_t>(Kr * 3));
        i64 si = 0;
        for (size_t r = 0; r < reach.size(); ++r) {
            const i64 m = reach[r];
            const double* src;
            i64 n, Ks;
            if (inside_all[r]) {
                src = V + m * K * 3;
                n = counts[m];
                Ks = K;
            } else {
                src = Vc.data() + si * Kc * 3;
                n = cc[si];
                Ks = Kc;
                ++si;
            }
            if (n < 3) continue;
            if (n > Ks) throw std::logic_error("clipped count exceeds its width");
            for (i64 k = 0; k < Kr; ++k) {
                const i64 kk = k < n ? k : n - 1;
                for (int i = 0; i < 3; ++i) P3[3 * k + i] = src[3 * kk + i];
            }
            out.live.push_back(m);
            out.cl.push_back(n);
            for (i64 k = 0; k < Kr; ++k) {
                const double* x = P3.data() + 3 * k;
                const double w = hdot(ew, x);
                out.UV.push_back(hdot(eu, x) / w);
                out.UV.push_back(hdot(ev, x) / w);
            }
        }
        std::vector<double>& UV = out.UV;
        const double tiny = std::numeric_limits<double>::min();
        // subnormal chart coordinates flushed to zero
        for (double& a : UV)
            if (std::fabs(a) < tiny) a = 0.0;
        // points within CHART_EDGE_ULPS ulps of the chart's edges snapped onto them
        const double near1 = edge_ulps * (std::nextafter(1.0, 2.0) - 1.0);
        for (const double val : {-1.0, 1.0})
            for (double& a : UV)
                if (std::fabs(a - val) <= near1) a = val;
        if (side)
            for (size_t i = 1; i < UV.size(); i += 2)
                if (std::fabs(UV[i]) <= near1) UV[i] = 0.0;
        // and points along an edge within a few ulps of each other merged
        const std::vector<double> e01 = {-1.0, 1.0};
        const std::vector<double> e1 = side ? std::vector<double>{-1.0, 0.0, 1.0} : e01;
        std::vector<size_t> idx;
        std::vector<double> vals;
        for (int k = 0; k < 2; ++k) {
            const std::vector<double>& edge_vals = k == 0 ? e1 : e01;
            for (const double val : edge_vals) {
                idx.clear();
                for (size_t i = 0; i < UV.size() / 2; ++i)
                    if (UV[2 * i + (1 - k)] == val) idx.push_back(2 * i + k);
                if (idx.size() <= 1) continue;
                vals.resize(idx.size());
                for (size_t i = 0; i < idx.size(); ++i) vals[i] = UV[idx[i]];
                merge_close(vals, edge_ulps);
                for (size_t i = 0; i < idx.size(); ++i) UV[idx[i]] = vals[i];
            }
        }
    }
    // ---- the faces' frustum clipper (exactff.methods._raster.FaceClip), the polar
    // plane's rays and the disk's ellipse arcs ----

    static i64 check_vertices(const Doubles& V,
                              const Ints& counts) {
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

    static i64 check_face_bucket(const Doubles& V,
                                 const Ints& counts,
                                 const Doubles& R,
                                 const Doubles& planes) {
        const i64 M = check_vertices(V, counts);
        if (R.ndim() != 2 || R.shape(0) != 3 || R.shape(1) != 3)
            throw std::invalid_argument("R must have shape (3, 3)");
        if (planes.ndim() != 2 || planes.shape(1) != 3)
            throw std::invalid_argument("planes must have shape (P, 3)");
        for (i64 k = 0; k < planes.size(); ++k) {
            const double h = planes.data()[k];
            if (h != 0.0 && h != 1.0 && h != -1.0)
                throw std::invalid_argument("planes' entries must be 0, 1 or -1");
        }
        return M;
    }

    void check_ids(const Ints& g_ids,
                   i64 M) const {
        if (g_ids.ndim() != 1 || g_ids.shape(0) != M)
            throw std::invalid_argument("g_ids must have shape (M,)");
        for (i64 m = 0; m < M; ++m)
            if (g_ids.data()[m] < 0 || g_ids.data()[m] >= n_live_)
                throw std::invalid_argument("g_ids out of range");
    }

    static py::tuple clipped_tuple(const Clipped& c) {
        const i64 L = static_cast<i64>(c.live.size());
        py::array_t<i64> live(L), cl(L);
        py::array_t<double> UV({L, c.K, static_cast<i64>(2)});
        std::copy(c.live.begin(), c.live.end(), live.mutable_data());
        std::copy(c.cl.begin(), c.cl.end(), cl.mutable_data());
        std::copy(c.UV.begin(), c.UV.end(), UV.mutable_data());
        return py::make_tuple(live, UV, cl);
    }

    // FaceClip: the vertices in the face's frame W = R x (each row's products added
    // first to second, then the third, as the numpy code writes it); the polygons that
    // reach the frustum (no plane with every vertex on or behind it) clipped plane by
    // plane (clip_halfspace: the planes' entries 0 and +-1 make h . W exact); the live
    // ones padded by their last vertex and projected, u = (scale W_0) / W_2,
    // v = (scale W_1) / W_2.
    static void clip_face(const double* V, i64 M, i64 K, const i64* counts, const double* R,
                          const double* planes, i64 n_planes, double scale, double meet_ulps,
                          Clipped& out) {
        std::vector<double> W(static_cast<size_t>(M * K * 3));
        for (i64 q = 0; q < M * K; ++q) {
            const double* x = V + 3 * q;
            for (int i = 0; i < 3; ++i)
                W[3 * q + i] = (x[0] * R[3 * i] + x[1] * R[3 * i + 1]) + x[2] * R[3 * i + 2];
        }
        std::vector<i64> reach;
        for (i64 m = 0; m < M; ++m) {
            const i64 n = counts[m];
            bool outside = false;
            for (i64 j = 0; j < n_planes && !outside; ++j) {
                bool all_out = true;
                for (i64 k = 0; k < n; ++k)
                    if (!(hdot(planes + 3 * j, W.data() + 3 * (m * K + k)) <= 0)) all_out = false;
                outside = all_out;
            }
            if (!outside && n >= 3) reach.push_back(m);
        }
        const i64 S = static_cast<i64>(reach.size());
        std::vector<double> Vc(static_cast<size_t>(S * K * 3));
        std::vector<i64> cc(static_cast<size_t>(S));
        for (i64 i = 0; i < S; ++i) {
            std::copy(W.data() + reach[i] * K * 3, W.data() + (reach[i] + 1) * K * 3,
                      Vc.data() + i * K * 3);
            cc[i] = counts[reach[i]];
        }
        i64 Kc = K;
        clip_planes(Vc, S, Kc, cc, planes, n_planes, meet_ulps);
        out.live.clear();
        out.cl.clear();
        out.UV.clear();
        out.K = Kc;
        for (i64 i = 0; i < S; ++i) {
            const i64 n = cc[i];
            if (n < 3) continue;
            out.live.push_back(reach[i]);
            out.cl.push_back(n);
            for (i64 k = 0; k < Kc; ++k) {
                const double* x = Vc.data() + 3 * (i * Kc + (k < n ? k : n - 1));
                out.UV.push_back((scale * x[0]) / x[2]);
                out.UV.push_back((scale * x[1]) / x[2]);
            }
        }
    }

    // the spans [X_1, X_2), [X_3, X_4), ... (X sorted, at most `slots` of them) as runs
    // of centres c (first centre at or above each end), each cell given to emit(col)
    template <class Emit>
    static void spans(const std::vector<double>& X, size_t slots, const double* c, i64 n,
                      Emit&& emit) {
        const size_t npairs = std::min(X.size() / 2, slots);
        for (size_t k = 0; k < npairs; ++k) {
            const i64 ia = std::lower_bound(c, c + n, X[2 * k]) - c;
            const i64 ib = std::lower_bound(c, c + n, X[2 * k + 1]) - c;
            for (i64 col = ia; col < ib; ++col) emit(col);
        }
    }

    // numpy's floor modulo of floats (np.remainder; the divisor positive)
    static inline double py_mod(double a, double b) {
        double m = std::fmod(a, b);
        if (m != 0.0) {
            if (m < 0.0) m += b;
        } else {
            m = 0.0;
        }
        return m;
    }

    // rasterise_polar on the clipped images c (live bucket indices into src)
    void scan_polar(const Clipped& c, const i64* src, const double* radii, i64 nr,
                    const double* cs, const double* sn, i64 S, double* bt, i64* bs,
                    i64 pair_chunk, i64 depth_chunk) {
        const double PI = 3.141592653589793, TWO_PI = 2.0 * PI;
        const double step = TWO_PI / static_cast<double>(S);
        const i64 L = static_cast<i64>(c.live.size()), K = c.K;
        const i64 chunk = std::max<i64>(1, pair_chunk / std::max<i64>(K, 1));
        i64 pairs_in_chunk = 0;
        std::vector<double> A(static_cast<size_t>(2 * K)), B(static_cast<size_t>(2 * K));
        std::vector<double> X;
        X.reserve(static_cast<size_t>(K + 1));
        use_scratch();
        for (i64 m = 0; m < L; ++m) {
            const double* P = c.UV.data() + m * K * 2;
            const i64 n = c.cl[m];
            const i64 sm = src[c.live[m]];
            // every edge from its lower end point (y, then x)
            double lo0 = INF, lo1 = INF, hi0 = -INF, hi1 = -INF;
            bool nan = false;
            for (i64 e = 0; e < K; ++e) {
                const double* a = P + 2 * e;
                const double* b = e < n - 1 ? P + 2 * (e + 1) : P;
                if (e >= n) b = a;
                const bool swap = (b[1] < a[1]) || (b[1] == a[1] && b[0] < a[0]);
                if (swap) std::swap(a, b);
                A[2 * e] = a[0]; A[2 * e + 1] = a[1];
                B[2 * e] = b[0]; B[2 * e + 1] = b[1];
                if (std::isnan(P[2 * e]) || std::isnan(P[2 * e + 1])) nan = true;
                lo0 = std::min(lo0, P[2 * e]); hi0 = std::max(hi0, P[2 * e]);
                lo1 = std::min(lo1, P[2 * e + 1]); hi1 = std::max(hi1, P[2 * e + 1]);
            }
            if (nan) continue;
            // the sectors within the image's angular extent (all when its box holds
            // the centre), one sector of margin on either side
            i64 k0, k1;
            if (lo0 <= 0 && hi0 >= 0 && lo1 <= 0 && hi1 >= 0) {
                k0 = 0;
                k1 = S - 1;
            } else {
                const double mid = std::atan2((lo1 + hi1) / 2, (lo0 + hi0) / 2);
                const double cx[4] = {lo0, lo0, hi0, hi0}, cy[4] = {lo1, hi1, hi1, lo1};
                double omin = INF, omax = -INF;
                for (int q = 0; q < 4; ++q) {
                    const double off = py_mod(std::atan2(cy[q], cx[q]) - mid + PI, TWO_PI) - PI;
                    omin = std::min(omin, off);
                    omax = std::max(omax, off);
                }
                k0 = static_cast<i64>(std::ceil((mid + omin) / step - 0.5)) - 1;
                k1 = static_cast<i64>(std::floor((mid + omax) / step - 0.5)) + 1;
                k1 = std::min(k1, k0 + S - 1);
            }
            for (i64 kk = k0; kk <= k1; ++kk) {
                const i64 k = ((kk % S) + S) % S;
                const double cx = cs[k], sy = sn[k];
                X.clear();
                size_t crossings = 0;
                for (i64 e = 0; e < n; ++e) {
                    const double* a = A.data() + 2 * e;
                    const double* b = B.data() + 2 * e;
                    // the edge's crossing with the ray (cos phi, sin phi) rho, rho > 0
                    const double sa = cx * a[1] - sy * a[0];
                    const double sb = cx * b[1] - sy * b[0];
                    if ((sa > 0) == (sb > 0)) continue;
                    const double t = sa / (sa - sb);
                    const double xx = a[0] + t * (b[0] - a[0]);
                    const double yy = a[1] + t * (b[1] - a[1]);
                    const double rho = cx * xx + sy * yy;
                    if (!(rho > 0)) continue;
                    X.push_back(rho);
                    ++crossings;
                }
                // an odd count: the centre is inside, the first span starts at 0
                if (crossings % 2 == 1) X.push_back(-INF);
                std::sort(X.begin(), X.end());
                spans(X, static_cast<size_t>((K + 1) / 2), radii, nr,
                      [&](i64 ring) { add(ring * S + k, sm, bt, bs, depth_chunk); });
                if (++pairs_in_chunk == chunk) {
                    flush(bt, bs);
                    pairs_in_chunk = 0;
                }
            }
        }
        flush(bt, bs);
    }

    // the disk's polygons: clipped to the horizon (x and y swapped), whether each
    // passes near the point, and per monotone piece of its arcs what the crossings need
    struct Horizon {
        std::vector<i64> live;        // bucket indices of the clipped polygons left
        std::vector<char> near;       // passes within near_rel of the point
        std::vector<i64> cc;          // their vertex counts
        std::vector<double> Vc;       // (live, K, 3), padded by the last vertex
        i64 K = 0;
    };

    static inline double dot_seq(const double* a, const double* b) {
        return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
    }

    // numpy's maximum and minimum (a NaN propagates)
    static inline double np_max(double a, double b) {
        return (std::isnan(a) || std::isnan(b)) ? std::numeric_limits<double>::quiet_NaN()
                                                 : std::max(a, b);
    }
    static inline double np_min(double a, double b) {
        return (std::isnan(a) || std::isnan(b)) ? std::numeric_limits<double>::quiet_NaN()
                                                 : std::min(a, b);
    }
    static inline double np_sign(double x) {
        return x > 0 ? 1.0 : x < 0 ? -1.0 : x == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    }

    static void clip_horizon(const double* V, i64 M, i64 K, const i64* counts, double meet_ulps,
                             double near_rel, Horizon& h) {
        std::vector<double> Vs(static_cast<size_t>(M * K * 3));
        for (i64 q = 0; q < M * K; ++q) {
            Vs[3 * q] = V[3 * q + 1];
            Vs[3 * q + 1] = V[3 * q];
            Vs[3 * q + 2] = V[3 * q + 2];
        }
        std::vector<i64> cnt(counts, counts + M), nc;
        std::vector<double> out;
        const double ez[3] = {0.0, 0.0, 1.0};
        i64 Kn;
        clip_halfspace(Vs, M, K, cnt, ez, meet_ulps, out, Kn, nc);
        h.K = Kn;
        h.live.clear(); h.near.clear(); h.cc.clear(); h.Vc.clear();
        for (i64 m = 0; m < M; ++m) {
            const i64 n = nc[m];
            if (n < 3) continue;
            const double* P = out.data() + m * Kn * 3;
            // _passes_near_origin: an edge's closest point to the origin within
            // near_rel of its longer end point's distance
            bool near = false;
            for (i64 e = 0; e < n && !near; ++e) {
                const double* a = P + 3 * e;
                const double* b = P + 3 * ((e + 1) % n);
                const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
                const double dd = dot_seq(d, d);
                double s = -dot_seq(a, d) / dd;
                s = std::isnan(s) ? 0.0 : std::min(std::max(s, 0.0), 1.0);
                const double q[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
                const double closest = std::sqrt(dot_seq(q, q));
                const double scale = np_max(std::sqrt(dot_seq(a, a)), std::sqrt(dot_seq(b, b)));
                near = closest <= near_rel * scale;
            }
            h.live.push_back(m);
            h.near.push_back(near ? 1 : 0);
            h.cc.push_back(n);
            for (i64 k = 0; k < Kn; ++k) {
                const double* x = P + 3 * (k < n ? k : n - 1);
                h.Vc.insert(h.Vc.end(), x, x + 3);
            }
        }
    }

    // rasterise_disk's scan of the polygons h holds that are not near the point
    void scan_disk(const Horizon& h, const i64* src, const double* xc, i64 nx, const double* yc,
                   i64 ny, const i64* tab, double* bt, i64* bs, i64 pair_chunk,
                   i64 depth_chunk) {
        const i64 K = h.K, K2 = 2 * K;
        const i64 chunk = std::max<i64>(1, pair_chunk / std::max<i64>(K2, 1));
        i64 pairs_in_chunk = 0;
        // per monotone piece: its parameter interval, its end points' y, and the
        // edge's a, d = b - a, a.a, d.d, a.d
        std::vector<double> S0(K2), S1(K2), Y0(K2), Y1(K2), ax(K2), ay(K2), dx(K2), dy(K2),
            a2(K2), v2(K2), av(K2);
        std::vector<char> ok(K2);
        std::vector<double> ya(K), X;
        X.reserve(static_cast<size_t>(K2));
        use_scratch();
        for (size_t li = 0; li < h.live.size(); ++li) {
            if (h.near[li]) continue;
            const double* P = h.Vc.data() + li * K * 3;
            const i64 n = h.cc[li];
            const i64 sm = src[h.live[li]];
            // each vertex's y on the disk
            for (i64 e = 0; e < K; ++e) {
                const double* a = P + 3 * e;
                ya[e] = a[1] / std::sqrt(dot_seq(a, a));
            }
            for (i64 e = 0; e < K; ++e) {
                const bool slot = e < n;
                const i64 nxt = (e + 1) % n;
                const double* A = P + 3 * e;
                const double* B = slot ? P + 3 * nxt : A;
                double yv = ya[e], yb = slot ? ya[nxt] : ya[e];
                // every edge from its lower end point (y, then x, then z)
                const bool swap = (yb < yv) ||
                                  (yb == yv && (B[0] < A[0] || (B[0] == A[0] && B[2] < A[2])));
                if (swap) {
                    std::swap(A, B);
                    std::swap(yv, yb);
                }
                const double d[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]};
                const double ad = dot_seq(A, d), aa = dot_seq(A, A), ddd = dot_seq(d, d);
                // the arc's extreme in y: d/ds y(s) = 0 is linear in s
                double s_ext = (A[1] * ad - d[1] * aa) / (d[1] * ad - A[1] * ddd);
                const bool inner = s_ext > 0 && s_ext < 1 && slot;
                double y_ext = yb;
                if (inner) {
                    const double q[3] = {A[0] + s_ext * d[0], A[1] + s_ext * d[1],
                                         A[2] + s_ext * d[2]};
                    y_ext = q[1] / std::sqrt(dot_seq(q, q));
                } else {
                    s_ext = 1.0;
                }
                // monotone pieces: [0, s_ext] from yv to y_ext, [s_ext, 1] from y_ext to yb
                S0[e] = 0.0; S1[e] = s_ext; Y0[e] = yv; Y1[e] = y_ext; ok[e] = slot;
                S0[K + e] = s_ext; S1[K + e] = 1.0; Y0[K + e] = y_ext; Y1[K + e] = yb;
                ok[K + e] = inner;
                for (const i64 j : {e, K + e}) {
                    ax[j] = A[0]; ay[j] = A[1]; dx[j] = d[0]; dy[j] = d[1];
                    a2[j] = aa; v2[j] = ddd; av[j] = ad;
                }
            }
            double lo = INF, hi = -INF;
            bool lo_nan = false, hi_nan = false;
            for (i64 j = 0; j < K2; ++j) {
                if (!ok[j]) continue;
                const double mn = np_min(Y0[j], Y1[j]), mx = np_max(Y0[j], Y1[j]);
                if (std::isnan(mn)) lo_nan = true; else lo = std::min(lo, mn);
                if (std::isnan(mx)) hi_nan = true; else hi = std::max(hi, mx);
            }
            // the scanlines within [lo, hi] (numpy's searchsorted puts NaN last)
            const i64 j0 = lo_nan ? nx : std::lower_bound(xc, xc + nx, lo) - xc;
            const i64 j1 = hi_nan ? nx : std::upper_bound(xc, xc + nx, hi) - xc;
            for (i64 r = j0; r < j1; ++r) {
                const double y = xc[r];
                X.clear();
                for (i64 j = 0; j < K2; ++j) {
                    if (!ok[j] || ((Y0[j] > y) == (Y1[j] > y))) continue;
                    // the crossing: (a_y + s d_y)^2 = y^2 |a + s d|^2, a quadratic in s
                    const double yy = y * y;
                    const double q2 = dy[j] * dy[j] - yy * v2[j];
                    const double q1 = 2.0 * (ay[j] * dy[j] - yy * av[j]);
                    const double q0 = ay[j] * ay[j] - yy * a2[j];
                    const double disc = std::sqrt(np_max(q1 * q1 - 4.0 * q2 * q0, 0.0));
                    // the two roots, in the cancellation-free forms; q2 = 0: one root
                    const double big = -0.5 * (q1 + std::copysign(disc, q1));
                    const double cand[3] = {big / q2, q0 / big, -q0 / q1};
                    const double s0 = S0[j], s1 = S1[j];
                    // the root on the piece and on the row's side, the nearest the piece
                    double best_s = 0.5 * (s0 + s1), best_d = INF;
                    for (const double cd : cand) {
                        const bool side = np_sign(ay[j] + cd * dy[j]) == np_sign(y) || y == 0;
                        double dist = np_max(np_max(s0 - cd, cd - s1), 0.0);
                        dist = (std::isfinite(cd) ? dist : INF) + (side ? 0.0 : 1.0);
                        if (dist < best_d) {
                            best_s = cd;
                            best_d = dist;
                        }
                    }
                    const double s = np_min(np_max(best_s, s0), s1);
                    const double x = (ax[j] + s * dx[j]) /
                                     std::sqrt(a2[j] + s * (2.0 * av[j] + s * v2[j]));
                    if (!std::isnan(x)) X.push_back(x);
                }
                std::sort(X.begin(), X.end());
                spans(X, static_cast<size_t>(K), yc, ny, [&](i64 col) {
                    const i64 cell = tab[r * ny + col];
                    if (cell >= 0) add(cell, sm, bt, bs, depth_chunk);
                });
                if (++pairs_in_chunk == chunk) {
                    flush(bt, bs);
                    pairs_in_chunk = 0;
                }
            }
        }
        flush(bt, bs);
    }

    // _zbuffer_chart on the clipped images c
    void scan_rays(const Clipped& c, const i64* src, const i64* cells, const double* cu,
                   const double* cv, i64 nb, double v_lo, const i64* order, const i64* starts,
                   double* bt, i64* bs, i64 pair_chunk) {
        const i64 L = static_cast<i64>(c.live.size()), K = c.K;
        const double fnb = static_cast<double>(nb);
        // (polygon, bucket) pairs: the buckets under each image's bounding box
        std::vector<double> box(static_cast<size_t>(4 * L));
        std::vector<i64> pb_poly, pb_b, cum;
        auto bucket = [&](double x) {
            // numpy's astype(int) truncates; then clipped to the grid
            const i64 b = static_cast<i64>(x);
            return std::min(std::max<i64>(b, 0), nb - 1);
        };
        i64 total = 0;
        for (i64 m = 0; m < L; ++m) {
            const double* P = c.UV.data() + m * K * 2;
            double lo0 = INF, lo1 = INF, hi0 = -INF, hi1 = -INF;
            for (i64 e = 0; e < K; ++e) {
                lo0 = np_min(lo0, P[2 * e]); hi0 = np_max(hi0, P[2 * e]);
                lo1 = np_min(lo1, P[2 * e + 1]); hi1 = np_max(hi1, P[2 * e + 1]);
            }
            box[4 * m] = lo0; box[4 * m + 1] = lo1; box[4 * m + 2] = hi0; box[4 * m + 3] = hi1;
            const i64 bx0 = bucket((lo0 + 1.0) * 0.5 * fnb), bx1 = bucket((hi0 + 1.0) * 0.5 * fnb);
            const i64 by0 = bucket((lo1 - v_lo) / (1.0 - v_lo) * fnb);
            const i64 by1 = bucket((hi1 - v_lo) / (1.0 - v_lo) * fnb);
            const i64 nby = by1 - by0 + 1, nbk = (bx1 - bx0 + 1) * nby;
            for (i64 k = 0; k < nbk; ++k) {
                const i64 b = (bx0 + k / nby) * nb + by0 + k % nby;
                pb_poly.push_back(m);
                pb_b.push_back(b);
                total += starts[b + 1] - starts[b];
                cum.push_back(total);
            }
        }
        // chunks of about pair_chunk (polygon, direction) pairs, as the numpy code cuts
        // them: bounds = [0] + searchsorted(cum, range(pair_chunk, total, pair_chunk),
        // "right") + [pairs]
        const i64 n_pairs = static_cast<i64>(pb_b.size());
        std::vector<i64> bounds{0};
        for (i64 x = pair_chunk; x < total; x += pair_chunk)
            bounds.push_back(std::upper_bound(cum.begin(), cum.end(), x) - cum.begin());
        bounds.push_back(n_pairs);
        use_scratch();
        const i64 no_chunk = std::numeric_limits<i64>::max();
        for (size_t q = 0; q + 1 < bounds.size(); ++q) {
            for (i64 p = bounds[q]; p < bounds[q + 1]; ++p) {
                const i64 m = pb_poly[p], b = pb_b[p];
                const double* P = c.UV.data() + m * K * 2;
                const double* bx = box.data() + 4 * m;
                const i64 sm = src[c.live[m]];
                const i64 ncl = c.cl[m];
                for (i64 j = starts[b]; j < starts[b + 1]; ++j) {
                    const i64 cl = order[j];
                    const double uu = cu[cl], vv = cv[cl];
                    if (!(uu >= bx[0] && uu <= bx[2] && vv >= bx[1] && vv <= bx[3])) continue;
                    // the crossing number over the edges, each from its lower end
                    // point (the padding's zero-length edges cross nothing: the
                    // polygon's own edges, the last one closing it)
                    bool inside = false;
                    for (i64 e = 0; e < ncl; ++e) {
                        const double* a = P + 2 * e;
                        const double* d = P + 2 * (e + 1 < ncl ? e + 1 : 0);
                        const bool straddles = (a[1] > vv) != (d[1] > vv);
                        if (!straddles) continue;
                        if (a[1] > d[1]) std::swap(a, d);
                        const double ux = a[0] + (vv - a[1]) * (d[0] - a[0]) / (d[1] - a[1]);
                        if (uu < ux) inside = !inside;
                    }
                    if (inside) add(cells[cl], sm, bt, bs, no_chunk);
                }
            }
            // resolve_depths once per chunk
            flush(bt, bs);
        }
    }

    // the depth buffer, checked, as pointers (the depths, the polygons shown)
    std::pair<double*, i64*> writable(py::array& best_t, py::array& best) const {
        check_buffer(best_t, best);
        return {static_cast<double*>(best_t.mutable_data()), static_cast<i64*>(best.mutable_data())};
    }

    // the layout's cell of each grid cell: one row per scanline, one column per centre
    static void check_table(const Ints& table, i64 rows, i64 cols) {
        if (table.ndim() != 2 || table.shape(0) != rows || table.shape(1) != cols)
            throw std::invalid_argument("table must have shape (scanlines, centres): (" +
                                        std::to_string(rows) + ", " + std::to_string(cols) + ")");
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

    // every vertex of polygon q (scene index) within the near-coplanar band of p's
    // plane: |n . x - d| <= BSP_COPLANAR_ULPS u (|n| . |x| + |d|)
    bool within(i64 p, i64 q) const {
        const double* n = N_.data() + 3 * p;
        const double d = Dp_.data()[p];
        const i64* off = offsets_.data();
        const double* V = V_.data();
        const double w = coplanar_ulps_ * EPS;
        for (i64 i = off[q]; i < off[q + 1]; ++i) {
            const double* x = V + 3 * i;
            const double mag = absdot3(x, n) + std::fabs(d);
            if (!(std::fabs(dot3(x, n) - d) <= w * mag)) return false;
        }
        return true;
    }

    // exactff.predicates.coplanar_pairs for live polygons (cached per pair)
    bool coplanar(i64 a, i64 b) {
        const i64 lo = std::min(a, b), hi = std::max(a, b);
        const std::uint64_t key = (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint64_t>(hi);
        // neighbouring cells mostly ask about the same pair
        if (key == last_key_) return last_value_;
        auto it = cache_.find(key);
        bool r;
        if (it != cache_.end()) {
            r = it->second;
        } else {
            const i64 pa = ids_.data()[a], pb = ids_.data()[b];
            r = within(pa, pb) || within(pb, pa);
            cache_.emplace(key, r);
        }
        last_key_ = key;
        last_value_ = r;
        return r;
    }

    // this thread's scratch for a call (the buffer's cells), the chunk's candidates
    void use_scratch() {
        Scratch& sc = scratch(n_cells_);
        sc_ = sc.cell.data();
        t_min_ = sc.t_min.data();
        touched_ = sc.touched.data();
        n_touched_ = 0;
        cand_.clear();
        in_chunk_ = 0;
    }

    // resolve_depths on the buffered candidates
    // one candidate (cell, live polygon) of the current chunk: its depth, the cell's
    // nearest depth so far; a ray along its polygon's plane hits nothing
    inline void add(i64 cell, i64 s, double* best_t, i64* best, i64 depth_chunk) {
        const double den = dot3(nl_p_ + 3 * s, D_p_ + 3 * cell);
        const double t = dl_p_[s] / den;
        if (std::isfinite(t)) {
            // (without branches on the depths: they do not predict)
            double& tm = t_min_[cell];
            touched_[n_touched_] = cell;
            n_touched_ += tm == INF;
            tm = t < tm ? t : tm;
            cand_.push_back(Candidate{t, den, static_cast<std::int32_t>(cell),
                                      static_cast<std::int32_t>(s)});
        }
        // the numpy code's chunks count every candidate, hit or not
        if (++in_chunk_ == depth_chunk) flush(best_t, best);
    }

    // resolve_depths on the chunk's candidates, merged into the buffer
    void flush(double* best_t, i64* best) {
        in_chunk_ = 0;
        const size_t n = cand_.size();
        if (n == 0) return;
        const double* Dn = Dnorm_.data();
        const double* dl = dl_.data();
        const double* band = band_.data();
        const i64* prio = prio_.data();
        CellScratch* sc = sc_;
        const double* tmin = t_min_;
        const Candidate* cd = cand_.data();
        // one of the polygons at the nearest depth (the last, as numpy's assignment),
        // and of the polygons there the one of lowest priority (priorities are
        // distinct per polygon; a polygon is a candidate of a cell once in a chunk)
        for (size_t k = 0; k < n; ++k) {
            if (cd[k].t == tmin[cd[k].cell]) {
                CellScratch& c = sc[cd[k].cell];
                const i64 s = cd[k].s;
                c.near = s;
                if (prio[s] < c.p_min) {
                    c.p_min = prio[s];
                    c.pick = s;
                }
            }
        }
        // ties: within four times the tie test's band of the nearest depth, and
        // coplanar with the polygon there
        const double slack_ulps = tie_slack_ulps_;
        for (size_t k = 0; k < n; ++k) {
            const i64 cell = cd[k].cell, s = cd[k].s;
            const double t_near = tmin[cell];
            if (cd[k].t == t_near) continue;
            const double slack = 4.0 * (band[s] + EPS * (slack_ulps * std::fabs(t_near) * Dn[cell]
                                                         + std::fabs(dl[s])));
            if (std::fabs(t_near - cd[k].t) * std::fabs(cd[k].den) <= slack) {
                CellScratch& c = sc[cell];
                if (coplanar(c.near, s) && prio[s] < c.p_min) {
                    c.p_min = prio[s];
                    c.pick = s;
                }
            }
        }
        // merge with the cells' best so far: the nearer wins unless the other is
        // coplanar with it and of lower priority
        for (i64 q = 0; q < n_touched_; ++q) {
            const i64 cell = touched_[q];
            CellScratch& c = sc[cell];
            const i64 s = c.pick;
            if (s >= 0) {
                const double t = tmin[cell];
                const i64 old = best[cell];
                const bool has_old = old >= 0;
                const bool new_nearer = t < best_t[cell];
                bool take;
                if (!has_old)
                    take = true;
                else if (new_nearer)
                    take = prio[s] < prio[old] || !coplanar(old, s);
                else
                    take = prio[s] < prio[old] && coplanar(s, old);
                if (t < best_t[cell]) best_t[cell] = t;
                if (take) best[cell] = s;
            }
            c = CellScratch();
            t_min_[cell] = INF;
        }
        cand_.clear();
        n_touched_ = 0;
    }

    Doubles D_, Dnorm_, nl_, dl_, band_;
    Ints prio_;
    Doubles V_;
    Ints offsets_;
    Doubles N_, Dp_;
    Ints ids_;
    double coplanar_ulps_, tie_slack_ulps_, clip_meet_ulps_, chart_edge_ulps_;
    i64 n_cells_ = 0, n_live_ = 0;
    // candidates of the current chunk
    std::vector<Candidate> cand_;
    i64 in_chunk_ = 0;                       // candidates in the chunk, hit or not
    // this thread's per-cell scratch (use_scratch), the cells the chunk touched
    CellScratch* sc_ = nullptr;
    double* t_min_ = nullptr;
    i64* touched_ = nullptr;
    i64 n_touched_ = 0;
    const double *D_p_ = nullptr, *nl_p_ = nullptr, *dl_p_ = nullptr;
    std::unordered_map<std::uint64_t, bool> cache_;
    std::uint64_t last_key_ = ~std::uint64_t(0);
    bool last_value_ = false;
};

}  // namespace

namespace {

// A row from its depth buffer: F[j] = the sum of the weights of the cells showing
// polygon j (best: live indices, ids: their scene indices), where j receives, added
// cell by cell in the cells' order (np.bincount's sums); and the number of cells that
// show a polygon.
py::tuple row_sums(Ints best, Ints ids, Bools receives, Doubles weights, i64 n) {
    const i64 C = best.shape(0), L = ids.shape(0);
    if (weights.shape(0) != C) throw std::invalid_argument("best and weights differ in length");
    if (receives.shape(0) != n) throw std::invalid_argument("receives must have shape (n,)");
    for (i64 k = 0; k < L; ++k)
        if (ids.data()[k] < 0 || ids.data()[k] >= n)
            throw std::invalid_argument("ids out of range");
    for (i64 c = 0; c < C; ++c)
        if (best.data()[c] >= L) throw std::invalid_argument("best out of range");
    py::array_t<double> F(n);
    double* f = F.mutable_data();
    i64 hit = 0;
    {
        py::gil_scoped_release release;
        std::fill(f, f + n, 0.0);
        const i64* b = best.data();
        const i64* id = ids.data();
        const bool* r = receives.data();
        const double* w = weights.data();
        for (i64 c = 0; c < C; ++c) {
            if (b[c] < 0) continue;
            ++hit;
            const i64 j = id[b[c]];
            if (r[j]) f[j] += w[c];
        }
    }
    return py::make_tuple(F, hit);
}

}  // namespace

PYBIND11_MODULE(_zbuffer, m) {
    m.doc() = "The compiled z-buffer of the discrete methods: scan conversion and depth test.";
    py::class_<ZBuffer>(m, "ZBuffer")
        .def(py::init<Doubles,
                      Doubles,
                      Doubles,
                      Doubles,
                      Doubles,
                      Ints,
                      Doubles,
                      Ints,
                      Doubles,
                      Doubles,
                      Ints, double,
                      double, double, double>(),
             py::arg("D"), py::arg("Dnorm"), py::arg("nl"), py::arg("dl"), py::arg("band"),
             py::arg("prio"), py::arg("V"), py::arg("offsets"), py::arg("N"), py::arg("Dp"),
             py::arg("ids"), py::arg("coplanar_ulps"), py::arg("tie_slack_ulps"),
             py::arg("clip_meet_ulps"), py::arg("chart_edge_ulps"))
        .def("face", &ZBuffer::face, py::arg("UV"), py::arg("cl"), py::arg("src"),
             py::arg("uc"), py::arg("vc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("candidates", &ZBuffer::candidates, py::arg("cell"), py::arg("src"),
             py::arg("best_t"), py::arg("best"), py::arg("depth_chunk"))
        .def("chart_face", &ZBuffer::chart_face, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("planes"), py::arg("eu"), py::arg("ev"), py::arg("ew"),
             py::arg("side"), py::arg("uc"), py::arg("vc"), py::arg("table"),
             py::arg("best_t"), py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("clipped_face", &ZBuffer::clipped_face, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("R"), py::arg("planes"), py::arg("scale"),
             py::arg("uc"), py::arg("vc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("polar", &ZBuffer::polar, py::arg("V"), py::arg("counts"), py::arg("g_ids"),
             py::arg("R"), py::arg("planes"), py::arg("scale"), py::arg("radii"),
             py::arg("cos"), py::arg("sin"), py::arg("best_t"), py::arg("best"),
             py::arg("pair_chunk"), py::arg("depth_chunk"))
        .def("disk", &ZBuffer::disk, py::arg("V"), py::arg("counts"), py::arg("g_ids"),
             py::arg("xc"), py::arg("yc"), py::arg("table"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("depth_chunk"),
             py::arg("near_rel"), py::arg("after_near") = false)
        .def("chart_rays", &ZBuffer::chart_rays, py::arg("V"), py::arg("counts"),
             py::arg("g_ids"), py::arg("planes"), py::arg("eu"), py::arg("ev"), py::arg("ew"),
             py::arg("side"), py::arg("cells"), py::arg("cu"), py::arg("cv"), py::arg("nb"),
             py::arg("v_lo"), py::arg("order"), py::arg("starts"), py::arg("best_t"),
             py::arg("best"), py::arg("pair_chunk"), py::arg("long_polygon"))
        .def("coplanar", &ZBuffer::coplanar_many, py::arg("a"), py::arg("b"));
    m.def("face_clip", &ZBuffer::face_clip, py::arg("V"), py::arg("counts"), py::arg("R"),
          py::arg("planes"), py::arg("scale"), py::arg("clip_meet_ulps"),
          "exactff.methods._raster.FaceClip of one bucket, compiled: (live, UV, cl).");
    m.def("row_sums", &row_sums, py::arg("best"), py::arg("ids"), py::arg("receives"),
          py::arg("weights"), py::arg("n"),
          "A row from its depth buffer: (F, cells that show a polygon); np.bincount's sums.");
    m.def("chart_clip", &ZBuffer::chart_clip, py::arg("V"), py::arg("counts"), py::arg("planes"),
          py::arg("eu"), py::arg("ev"), py::arg("ew"), py::arg("side"),
          py::arg("clip_meet_ulps"), py::arg("chart_edge_ulps"),
          "exactff.visibility.charts.chart_clip (margin 0) of one bucket, compiled: "
          "(live, UV, cl).");
}
