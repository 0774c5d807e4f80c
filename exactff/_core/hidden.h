// The hidden region of a receiver Q seen from many points of an emitter, as disjoint
// convex pieces, and the point form factors of the pieces (the area form factors'
// hidden parts, exactff/area/occluded.py): hidden.cpp.

#ifndef EXACTFF_CORE_HIDDEN_H
#define EXACTFF_CORE_HIDDEN_H

#include <cstdint>
#include <vector>

namespace exactff {

// Arguments: X (n, 3) points; corners (c, 3) the pyramid's convex base in Q's plane;
// q0 (3,) a point of the plane, nQ (3,) its unit normal towards the front, RQ (2, 3)
// the plane's axes; blockers (b, k, 3) padded convex polygons with counts (b,) and unit
// normals (b, 3), outward for the members of a convex solid; groups (b,) the solid of
// each (-1: none), back_face a distance beyond which x is off a member's plane (a solid's
// members that x sees from behind are skipped where it sees one from the front); edge_on
// a distance within which x is on a blocker's plane (seen edge-on, hiding nothing);
// vertex_ulps the rounding of an offset or a crossing in
// units of the working precision's roundoff of its length (of the longer end's, for a
// crossing); sliver_ulps: a piece of at most this many units of rounding of the squared
// reach (twice its area) is dropped and counted; max_pieces: a point with more pieces
// is reported lost; precise_rtol, extent: a point is computed again in long double
// where an image is not finite or the vertices' rounding can move its images by more
// than precise_rtol of the larger of their reach and extent (Q's size), unless what that
// moves of the value (moved * length * h / (pi r^3), the caller's estimate's term) is
// within precise_atol (negative: always again); parts (p, k', 2)
// padded convex parts of Q in the plane's frame with counts (p,), none where the base
// is Q itself; frame (3, 3) the receiving frame of the points (rows: two axes of the
// emitter's plane and its normal); c1, c2, eps the sector sums' error model; rings: also
// return the pieces (else xy, ring_start and ring_point are empty).
// Returns (xy (V, 2) ring vertices in the plane's frame, ring_start (R + 1,), ring_point
// (R,), lost (n,) bool: an image not finite or too many pieces, the point left empty
// for the caller, reach (n,) the largest coordinate of a point's images (before the
// booleans), length (n,) the pieces' perimeters, box (n, 4) their bounding box (the
// slivers' included), moved (n,) how far the rounding of the clipped vertices can move
// a point's images, dropped (n,) the area of its slivers, hidden (n,) the point form
// factor of the pieces (Eq. 3's sector sums over 2 pi), rounding (n,) its sector sums'
// rounding estimate, and back_faces: how many times a solid's member was skipped).
// The arrays are C-ordered; blocker_stride and part_stride are their padded lengths (k
// and k').
struct HiddenArgs {
    const double* X;
    std::int64_t n;
    const double* corners;
    std::int64_t n_corners;
    const double *q0, *nQ, *RQ;
    const double* blockers;
    std::int64_t n_blockers, blocker_stride;
    const long long* counts;
    const double* normals;
    const long long* groups;
    double back_face, edge_on, vertex_ulps, sliver_ulps;
    long long max_pieces;
    double precise_rtol, precise_atol, extent;
    const double* parts;
    std::int64_t n_parts, part_stride;
    const long long* part_counts;
    const double* frame;
    double c1, c2, eps;
    bool rings;
    // per point, the cell it lies in (a cell's points consecutive): the blockers that
    // add nothing to a region are settled once for a cell's box where they can be
    // (hidden.cpp's Hints; the same decisions as point by point); null: point by point
    const long long* cells = nullptr;
};

struct HiddenResult {
    std::vector<double> xy;
    std::vector<long long> ring_start, ring_point;
    std::vector<unsigned char> lost;
    std::vector<double> reach, length, box, moved, dropped, hidden, rounding;
    long long back_faces = 0;
};

HiddenResult hidden_pieces(const HiddenArgs& args);

}  // namespace exactff

#endif
