// The discrete methods' z-buffer (issue 55): the polygons of one bucket clipped to a
// face's or a chart's frustum (or to the horizon, for the disk), scan-converted on the
// face's grid of cells (or along the polar plane's rays, or per direction), and
// depth-tested into one row's depth buffer; and a row's sums from its buffer.
//
// It does what the numpy rasteriser does (exactff/methods/_raster.py, rasterise_face,
// and exactff/methods/_sampling.py, resolve_depths), cell for cell, so that the numpy
// code stays its test oracle:
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
//   components adds the first and third products, then the second), which is why the
//   arrays stay flat doubles in numpy's layout rather than vec.h's Vec3.
//
// The arrays are the caller's (C order, checked by the binding, bind_zbuffer.cpp); no
// function here takes the GIL.

#ifndef EXACTFF_CORE_ZBUFFER_H
#define EXACTFF_CORE_ZBUFFER_H

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace exactff {
namespace zbuffer {

using i64 = std::int64_t;

// A row's depth data. D (C, 3) cell directions, Dnorm (C,) their norms
// (np.linalg.norm, passed in so that they are numpy's); nl (L, 3), dl (L,), band (L,),
// prio (L,) the live polygons' depth data (ZBufferRow); V, offsets, N, Dp, ids the
// scene's polygons and planes and the live polygons' scene indices (the coplanar
// rule); coplanar_ulps: exactff._tolerances.BSP_COPLANAR_ULPS; tie_slack_ulps:
// ZBUFFER_ROUNDING_ULPS + 1; clip_meet_ulps, chart_edge_ulps: CLIP_MEET_ULPS and
// CHART_EDGE_ULPS (the chart clipper's).
struct RowData {
    const double *D, *Dnorm, *nl, *dl, *band;
    const i64* prio;
    const double* V;
    const i64* offsets;
    const double *N, *Dp;
    const i64* ids;
    i64 n_cells, n_live;
    double coplanar_ulps, tie_slack_ulps, clip_meet_ulps, chart_edge_ulps;
};

// One bucket of polygons in the row's local frame: V (M, K, 3), padded; counts (M,)
// their vertex counts; g_ids (M,) their live indices (null where not needed).
struct Bucket {
    const double* V;
    i64 M, K;
    const i64* counts;
    const i64* g_ids;
};

// A chart's exact frustum: planes (4, 3), axes eu, ev, ew (3,), whether it is a side chart
struct Chart {
    const double *planes, *eu, *ev, *ew;
    bool side;
};

// A face's frustum (exactff.methods._raster.FaceClip): R (3, 3) the face's frame
// (rows), planes (P, 3) the frustum in that frame (entries 0 and +-1), scale the face
// coordinates' factor
struct Face {
    const double* R;
    const double* planes;
    i64 n_planes;
    double scale;
};

// A face's grid: scanlines at centres u (nu,), spans over centres v (nv,), table
// (nu, nv) the layout's cell of each grid cell (-1: none)
struct Grid {
    const double* u;
    i64 nu;
    const double* v;
    i64 nv;
    const i64* table;
};

// The depth buffer written: the nearest depths (C,), the live polygons shown (C,), -1: none
struct Buffer {
    double* t;
    i64* best;
};

// The chunks of the numpy code: (polygon, scanline) pairs, candidates
struct Chunks {
    i64 pair, depth;
};

// A bucket's clipped images: live indices into the bucket, vertex counts, UV (live, K,
// 2) padded by the last vertex
struct Clipped {
    std::vector<i64> live, cl;
    std::vector<double> UV;
    i64 K = 0;
};

// The disk's polygons: clipped to the horizon (x and y swapped), whether each passes
// near the point, and their vertices
struct Horizon {
    std::vector<i64> live;        // bucket indices of the clipped polygons left
    std::vector<char> near;       // passes within near_rel of the point
    std::vector<i64> cc;          // their vertex counts
    std::vector<double> Vc;       // (live, K, 3), padded by the last vertex
    i64 K = 0;
};

// exactff.visibility.charts.chart_clip (margin 0) of one bucket
void clip_chart(const Bucket& b, const Chart& ch, double meet_ulps, double edge_ulps,
                Clipped& out);

// exactff.methods._raster.FaceClip of one bucket: the vertices in the face's frame, the
// polygons that reach the frustum clipped plane by plane, the live ones projected,
// u = (scale W_0) / W_2, v = (scale W_1) / W_2
void clip_face(const Bucket& b, const Face& f, double meet_ulps, Clipped& out);

// A row from its depth buffer: F[j] (n,) = the sum of the weights (C,) of the cells
// showing polygon j (best (C,): live indices below L, -1 none; ids (L,): their scene
// indices), where j receives, added cell by cell in the cells' order (np.bincount's
// sums); returns the number of cells that show a polygon, or -1 (F unfinished) where
// a cell's entry is L or more.
i64 row_sums(const i64* best, i64 C, const i64* ids, i64 L, const bool* receives,
             const double* weights, i64 n, double* F);

// ZBufferRow's live polygons of one bucket (exactff.methods._sampling): the vertices
// V (M, K, 3), padded, in the point's local frame, (x - p) R^T with each row's
// products added first to second, then the third (exactff.geometry.rotate); the
// polygons alive (not edge-on) with a vertex above the horizon (the largest local z
// of its counts[m] vertices > 0, none if one is NaN): their bucket indices and local
// vertices (live, K, 3)
void live_local(const double* V, i64 M, i64 K, const i64* counts, const bool* alive,
                const double* p, const double* R, std::vector<i64>& live,
                std::vector<double>& local);

// Monte Carlo's cosine-weighted directions (exactff.methods.monte_carlo): from uniform
// samples q1, q2 (n,) in [0, 1), the points (r cos a, r sin a) of the unit disk,
// r = sqrt q1, a = (2 pi) q2, lifted to the hemisphere, z = sqrt(max((1 - x x) - y y, 0))
// (1e-300 where 0), and normalised as CellLayout does, D / |D|; D (n, 3) and the norms
// of the normalised directions (n,), both np.linalg.norm's sqrt((x x + y y) + z z)
void cosine_directions(const double* q1, const double* q2, i64 n, double* D, double* norms);

// |d| of each direction as np.linalg.norm(D, axis=1) has it: sqrt((x x + y y) + z z)
void direction_norms(const double* D, i64 n, double* norms);

// One chart's directions for chart_rays (exactff.methods._sampling._chart_of and
// _cell_grid): the directions, renumbered chart by chart and bucket by bucket, at
// [offset, offset + count); their chart coordinates cu, cv in that order; the grid of
// nb x nb buckets over [-1, 1] x [v_lo, 1] and its CSR starts (nb nb + 1,)
struct RayChart {
    i64 chart = 0, offset = 0, count = 0, nb = 1;
    double v_lo = 0.0;
    std::vector<double> cu, cv;
    std::vector<i64> starts;
};

// The directions D (n, 3) sorted into the charts (_chart_of: axis (5, 3) the axes'
// components, sign_w (5,) the sign of e_w) and bucketed (_cell_grid, its margin
// `margin`): per non-empty chart a RayChart, and slot (n,), each direction's new index
void ray_charts(const double* D, i64 n, const i64* axis, const double* sign_w, double margin,
                std::vector<RayChart>& charts, i64* slot);

// the depth buffer's per-cell scratch within a chunk (the nearest depth apart: the
// candidates touch it, the other fields only the chunk's resolution)
struct CellScratch {
    i64 near = -1;                              // a polygon at the nearest depth
    i64 p_min = INT64_MAX;                      // the lowest priority tied
    i64 pick = -1;                              // its polygon
};

// a candidate (cell, live polygon) of the current chunk: its depth and n . d
struct Candidate {
    double t, den;
    std::int32_t cell, s;    // (24 bytes: the chunk's candidates are the buffer's traffic)
};

// a face's span within one chunk: grid row r, columns [a, b), live polygon s
struct Run {
    std::int32_t r, a, b, s;
};

// a scanline's cell within a chunk (scan's resolution row by row): CellScratch's
// fields and the nearest depth
struct RowCell {
    double t_min = INFINITY;
    i64 near = -1, p_min = INT64_MAX, pick = -1;
};

// a candidate of a scanline: its depth, n . d, its column and polygon
struct RowCandidate {
    double t, den;
    std::int32_t col, s;
};

// a scan's spans cut into chunks (zbuffer.cpp)
struct SpanChunks;

// One row's z-buffer: scan conversion of the buckets and the depth test into a Buffer.
class ZBuffer {
  public:
    explicit ZBuffer(const RowData& row) : row_(row) {}

    // M polygons already on a face, UV (M, K, 2) padded, counts cl, live indices src
    void face(const double* UV, i64 M, i64 K, const i64* cl, const i64* src, const Grid& g,
              Buffer buf, Chunks ch);
    // one bucket clipped to a chart's frustum first, then scanned on the chart's grid
    void chart_face(const Bucket& b, const Chart& c, const Grid& g, Buffer buf, Chunks ch);
    // candidate (cell, live polygon) pairs, in chunks of depth_chunk
    void candidates(const i64* cell, const i64* src, i64 n, Buffer buf, i64 depth_chunk);
    // one bucket clipped by a face's frustum first (clip_face), then scanned
    void clipped_face(const Bucket& b, const Face& f, const Grid& g, Buffer buf, Chunks ch);
    // the polar plane (rasterise_polar): one bucket clipped as clipped_face does, scanned
    // along every sector's ray; radii (nr,), the sectors' cos and sin (S,): the cell of
    // ring i and sector k is i S + k
    void polar(const Bucket& b, const Face& f, const double* radii, i64 nr, const double* cs,
               const double* sn, i64 S, Buffer buf, Chunks ch);
    // discrete PPBH (rasterise_disk): the bucket clipped to the horizon, the polygons
    // passing within near_rel of the point returned (bucket indices); the others scanned
    // (scanlines at g.u along the local y, spans along x over g.v) when there are none
    // near or after_near
    std::vector<i64> disk(const Bucket& b, const Grid& g, Buffer buf, Chunks ch,
                          double near_rel, bool after_near);
    // _zbuffer_chart for any directions: the bucket clipped to the chart, each image's
    // bounding box over the chart's grid of buckets of directions (cells (n,) the
    // directions' indices, cu, cv their chart coordinates, nb and v_lo the grid, order
    // and starts its CSR lists), the crossing number; false (and nothing done) where the
    // clipped images are wider than long_polygon vertices
    bool chart_rays(const Bucket& b, const Chart& c, const i64* cells, const double* cu,
                    const double* cv, i64 nb, double v_lo, const i64* order,
                    const i64* starts, Buffer buf, i64 pair_chunk, i64 long_polygon);
    // exactff.predicates.coplanar_pairs for live polygons a and b (cached per pair)
    bool coplanar(i64 a, i64 b);

  private:
    // a face's scan conversion: the spans of every (polygon, scanline) pair cut into the
    // numpy code's chunks (SpanChunks), resolved by resolve_chunks
    void scan(const double* uv, i64 M, i64 K, const i64* c, const i64* src, const i64* pos,
              const double* u, i64 nu, const double* v, i64 nv, const i64* tab, double* bt,
              i64* bs, i64 pair_chunk, i64 depth_chunk);
    // one scanline's runs of a chunk (runs[idx[k]]), resolved as flush does; the grid
    // row's cells base + col (simple) or trow[col]; L (nv,) and touched left cleared
    void resolve_row(const Run* runs, const std::int32_t* idx, i64 n_runs, bool simple,
                     i64 base, const i64* trow, RowCell* L, std::vector<RowCandidate>& cand,
                     std::vector<std::int32_t>& touched, double* best_t, i64* best);
    // the chunks of sc, each scanline by scanline (resolve_row), or, where grid cells
    // share a layout cell, candidate by candidate (add, flush)
    void resolve_chunks(const SpanChunks& sc, double* best_t, i64* best, i64 depth_chunk);
    void scan_polar(const Clipped& c, const i64* src, const double* radii, i64 nr,
                    const double* cs, const double* sn, i64 S, double* bt, i64* bs,
                    i64 pair_chunk, i64 depth_chunk);
    void scan_disk(const Horizon& h, const i64* src, const double* xc, i64 nx,
                   const double* yc, i64 ny, const i64* tab, double* bt, i64* bs,
                   i64 pair_chunk, i64 depth_chunk);
    void scan_rays(const Clipped& c, const i64* src, const i64* cells, const double* cu,
                   const double* cv, i64 nb, double v_lo, const i64* order, const i64* starts,
                   double* bt, i64* bs, i64 pair_chunk);
    bool within(i64 p, i64 q) const;
    void use_scratch();
    void add(i64 cell, i64 s, double* best_t, i64* best, i64 depth_chunk);
    void flush(double* best_t, i64* best);

    RowData row_;
    // candidates of the current chunk
    std::vector<Candidate> cand_;
    i64 in_chunk_ = 0;                       // candidates in the chunk, hit or not
    // this thread's per-cell scratch (use_scratch), the cells the chunk touched
    CellScratch* sc_ = nullptr;
    double* t_min_ = nullptr;
    i64* touched_ = nullptr;
    i64 n_touched_ = 0;
    std::unordered_map<std::uint64_t, bool> cache_;
    std::uint64_t last_key_ = ~std::uint64_t(0);
    bool last_value_ = false;
};

}  // namespace zbuffer
}  // namespace exactff

#endif
