// Which polygons may hide part of a receiver from an emitter, for a whole area row in
// one call (exactff/area/culling.py's shaft and hull_blockers, their reference): shaft
// culling (Haines & Wallace 1991) of every polygon against each pair's bounding box, the
// emitter's and the receiver's planes and the box edges' side planes, then the exact test
// against the faces of the convex hull of the pair's two parts.

#ifndef EXACTFF_CORE_ROW_CULLING_H
#define EXACTFF_CORE_ROW_CULLING_H

#include <cstdint>
#include <vector>

namespace exactff {
namespace area {

// the scene and the row, as culling.padded_polygons and area_row hold them
struct RowCullingArgs {
    const double* V;      // (n, kmax, 3): the polygons, short ones padded by repeats
    const double* lo;     // (n, 3), their boxes
    const double* hi;
    const double* N;      // (n, 3), their unit normals
    std::int64_t n, kmax;
    std::int64_t i;       // the emitter
    const double* nP;     // its unit normal and a point of its plane
    const double* p0;
    const std::int64_t* J;  // (m,) the receivers
    const double* boxes;    // (m, 4, 3): per pair the clipped emitter's lo, hi, the clipped receiver's lo, hi
    const double* VP;       // the pairs' clipped emitters and receivers, rings with offsets (m + 1)
    const std::int64_t* po;
    const double* VQ;
    const std::int64_t* qo;
    std::int64_t m;
    double near;          // AREA_HULL_RTOL of the scene's size
    double eps;           // the unit roundoff of doubles
    std::int64_t hull_points;   // AREA_HULL_MAX_POINTS: beyond, no hull test (every shaft survivor kept)
};

struct RowBlockers {
    std::vector<std::int64_t> blockers, start;   // per pair start[a] .. start[a + 1]
    std::vector<std::int64_t> boxed, left;       // per pair: in its box, left by the shaft
};

RowBlockers row_blockers(const RowCullingArgs& a);

}  // namespace area
}  // namespace exactff

#endif
