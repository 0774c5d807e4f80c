// One occluded pair of an area row, compiled (the area code's per-pair path,
// exactff/area/, docs/explanation/area-form-factors.md): the vertex-edge visibility
// events of the pair cut to segments of the emitter's plane (pair.cpp, event_lines), the
// curved events traced as chords (curved.cpp, curved_event_lines), and the emitter cut
// along them into cells (cut_cells).

#ifndef EXACTFF_CORE_PAIR_H
#define EXACTFF_CORE_PAIR_H

#include <cstdint>
#include <vector>

namespace exactff {

// Arguments of event_lines. S: the pair's polygons, the receiver's part first and then
// the blockers, their vertices concatenated in W (N, 3) with start (n + 1,) the offset of
// each; solid (n,) the convex solid of each for the pair (-1: none; empty: no solids);
// nP (3,) and dP the emitter's plane n . x = dP; frame (3, 3) the emitter's receiving frame
// (rows: two axes of its plane and its normal); c (3,) the centre and radius the radius
// of the disk (in P's plane) the lines are kept in; nQ, q0 (3,) the receiver's plane,
// RQ (2, 3) its axes, Q2 (q, 2) the receiver's part in that frame about q0 (the region
// the lines of sight of a blocker-blocker event must meet); shortcuts: cull the
// blocker-blocker events whose lines of sight miss Q2 and the vertex-edge pairs within one
// solid; ray_parallel (AREA_RAY_PARALLEL) and event_parallel (AREA_EVENT_PARALLEL): a ray
// or a plane that close to parallel to P's plane has no image there; line_ulps
// (AREA_EVENT_LINE_ULPS) and eps (EPS): a vertex that close to an edge's line makes no
// event with it.
struct EventArgs {
    const double* W;
    const std::int64_t* start;
    std::int64_t n;
    const std::int64_t* solid;   // null: no solids
    const double *nP, *frame, *c;
    double dP, radius;
    const double *nQ, *q0, *RQ, *Q2;
    std::int64_t n_q2;
    bool shortcuts;
    double ray_parallel, event_parallel, line_ulps, eps;
};

// The segments (m, 2, 2) in the frame's first two axes about c, each with its ends in
// lexicographic order and the list sorted and without copies (as numpy's unique of the
// rows), and what was culled: blocker-blocker vertex-edge rows whose lines of sight miss
// the receiver (culled_events) and vertex-edge rows within one solid (solid_events).
struct EventResult {
    std::vector<double> segments;
    long long culled_events = 0, solid_events = 0;
};

EventResult event_lines(const EventArgs& args);

// Arguments of curved_event_lines (exactff/area/curved.py's, the reference: the same steps
// in the same order). W, start, n, solid: the pair's polygons S as for EventArgs (the
// receiver's part first, its solid unused); Qc (q, 3) the receiver's part in front of P;
// nP, dP, frame, c, radius as for EventArgs; atol the pair's absolute tolerance (the
// chords' deviation within sqrt(atol) of radius where less than curve_rtol of it);
// hull_rtol (AREA_HULL_RTOL), event_parallel (AREA_EVENT_PARALLEL), extend_rtol
// (AREA_CUT_EXTEND_RTOL), samples (AREA_CURVED_EVENT_SAMPLES), bisections
// (AREA_CURVED_EVENT_BISECTIONS), max_triples (AREA_CURVED_MAX_TRIPLES), curve_rtol
// (AREA_CURVED_EVENT_RTOL), chord_split (AREA_CURVED_CHORD_SPLIT), chord_halvings
// (AREA_CURVED_CHORD_HALVINGS), rows_per_call (AREA_EVENT_ROWS_PER_CALL: the reference's
// batches, over each of which its bisections stop together).
struct CurvedArgs {
    const double* W;
    const std::int64_t* start;
    std::int64_t n;
    const std::int64_t* solid;   // null: no solids
    const double* Qc;
    std::int64_t n_q;
    const double *nP, *frame, *c;
    double dP, radius, atol;
    double hull_rtol, event_parallel, extend_rtol, curve_rtol, chord_split;
    std::int64_t samples, bisections, max_triples, chord_halvings, rows_per_call;
};

// The chords (m, 2, 2) in the frame's first two axes about c, in the reference's order;
// events: the curves cut along; skipped: more than max_triples triples (none traced).
struct CurvedResult {
    std::vector<double> segments;
    long long events = 0;
    bool skipped = false;
};

CurvedResult curved_event_lines(const CurvedArgs& args);

// The emitter cut along the event lines as a 2-D arrangement (no GEOS): P2 (k, 2) the
// emitter's part, convex and counter-clockwise, in the events' frame; segments (m, 2, 2)
// the event lines; step: a cut line's end within step of P's boundary is moved onto it
// (the crossing of its line with the boundary), the rest of P's boundary is left as is;
// merge: nodes closer than this are one; sliver: cells of at most this area are dropped.
// Collinear lines are joined first (their union along the line, as one line: within merge
// of each other's line and overlapping), so that the noding's cost is that of the lines
// themselves, not of their copies. Returns the cells' triangles (t, 3, 2),
// counter-clockwise, the cells' areas, the number of lines noded (P's edges and the
// joined lines inside P), and ok: false where the
// arrangement is not one this builds (P not convex, a cell with a hole, a face no ear
// clips), for the caller to cut P another way.
struct CellResult {
    std::vector<double> triangles;
    std::vector<double> areas;
    long long lines = 0;
    bool ok = true;
};

CellResult cut_cells(const double* P2, std::int64_t k, const double* segments, std::int64_t m,
                     double step, double merge, double sliver);

}  // namespace exactff

#endif
