// The set-up of an occluded pair's hidden parts, compiled (exactff/area/hidden.py,
// hidden_setup, which stays the reference and takes the cases this declines): the
// receiver's part Qc's frame, the blockers clipped to the front of its plane
// (halfspace.py, clip_front and clip_halfspace), their unit normals (outward for the
// members of a convex solid) and solids, the box of the blockers and Qc, and Qc's size in
// its plane; the arguments hidden.h's hidden_pieces takes.

#ifndef EXACTFF_CORE_HIDDEN_SETUP_H
#define EXACTFF_CORE_HIDDEN_SETUP_H

#include <cstdint>
#include <vector>

namespace exactff {

// Arguments: Qc (q, 3); the blockers' vertices concatenated in W (N, 3) with start
// (b + 1,) the offset of each; solid (b,) each blocker's convex solid for the pair (-1:
// none) and inner (b, 3) a point inside its hull (NaN: its members are not all
// blockers), or both null; eps (EPS), convex_ulps (CONVEX_TURN_ULPS), meet_ulps
// (CLIP_MEET_ULPS), normal_floor (halfspace.py's NORMAL_FLOOR), strict_turn
// (AREA_STRICT_TURN), hull_rtol (AREA_HULL_RTOL).
struct SetupArgs {
    const double* Qc;
    std::int64_t n_q;
    const double* W;
    const std::int64_t* start;
    std::int64_t n;
    const std::int64_t* solid;
    const double* inner;
    double eps, convex_ulps, meet_ulps, normal_floor, strict_turn, hull_rtol;
};

// status 0: the set-up (each blocker in front of Qc's plane one convex piece: V (m, k,
// 3) padded by repeating the last vertex, counts (m,), unit normals NK (m, 3), group
// (m,) the solid labelled 0, 1, ... or -1; kept (m,) the blocker each is); 1: no
// blocker in front (no set-up); 2: declined (Qc not strictly convex, or a blocker's part
// in front not convex), for the reference to build. nQ, q0 (3,), RQ (3, 3) Qc's frame;
// lo, hi (3,) the box; extent Qc's size in its plane.
struct SetupResult {
    int status = 0;
    double nQ[3], q0[3], RQ[9], lo[3], hi[3];
    double extent = 0;
    std::int64_t stride = 0;
    std::vector<double> V, NK;
    std::vector<long long> counts, group, kept;
};

SetupResult hidden_setup(const SetupArgs& args);

}  // namespace exactff

#endif
