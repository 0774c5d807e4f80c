// One occluded pair of an area row in one compiled call (exactff/area/adaptive.py,
// _hidden_integral, which stays the reference and takes the pairs this declines;
// docs/explanation/area-form-factors.md): the emitter's and the receiver's frames, the
// vertex-edge and curved events (pair.h), the count of their distinct lines, the emitter
// cut into cells (pair.h), the blockers in the receiver's plane dropped and the hidden
// set-up (hidden_setup.h), the cells' corners first and the adaptive levels (levels.h),
// the check of the rules' sum on the unoccluded point values, and the value with its
// estimate. Every step is the reference's in the same order and with the same roundings
// (numpy's sums are pairwise, its matrix products those of the BLAS: numpy_ops.h), so
// that the value and estimate are the reference's to the bit.

#ifndef EXACTFF_CORE_OCCLUDED_PAIR_H
#define EXACTFF_CORE_OCCLUDED_PAIR_H

#include <cstdint>
#include <vector>

#include "levels.h"

namespace exactff {

// The tolerances the pair reads (exactff/_tolerances.py, by the same names) and the
// levels' rules (levels.h's order), set once for many pairs.
struct PairConstants {
    double hidden_pad, ray_parallel, event_parallel, event_line_ulps, hull_rtol, extend_rtol,
        curve_rtol, chord_split, event_line_key, sliver_cell, cell_cover_rtol,
        cell_cover_atol_share, low_rules_tolerance,
        coplanar_ulps, eps, bound_cos_slack, bound_spread_ulps, unevaluated_share,
        unevaluated_least;
    std::int64_t samples, bisections, max_triples, chord_halvings, rows_per_call,
        umbra_min_lines, max_event_lines, many_cells;
    // hidden_setup.h's
    double convex_ulps, meet_ulps, normal_floor, strict_turn;
    // levels.h's (LevelArgs and its HiddenArgs)
    double vertex_ulps, sliver_ulps, precise_rtol, c1, c2, sliver_share, budget_share,
        back_face_rtol, edge_on_rtol, precise_share, boolean_ulps, image_rtol, offset_ulps,
        small_share, small_reach, null_factor;
    long long max_pieces, max_depth, points_per_call;
    TriangleRule rules[kLevelRules];
    // whether numpy's BLAS fuses the multiply-adds of a vector's dot product, of a
    // (k, 3) @ (3, m) product and of a (t, 3, 2) @ (2, 3) one (numpy_ops.h)
    bool fused_dot, fused_matmul, fused_stacked;
};

// One pair: S the receiver's whole polygon and the blockers, their vertices in W (N, 3)
// with start (n + 1,); solid (n,) the convex solid of each (-1: none) and inner (n, 3) a
// point inside it, or both null; Pc (p, 3) the emitter's part, Qc (q, 3) the receiver's
// part in front of it, nP (3,) the emitter's unit normal; atol the pair's absolute
// tolerance, area_P the emitter's area, whole the pair's unoccluded value and estimate
// (per unit area of P).
struct PairArgs {
    const double* W;
    const std::int64_t* start;
    std::int64_t n;
    const std::int64_t* solid;
    const double* inner;
    const double* Pc;
    std::int64_t n_p;
    const double* Qc;
    std::int64_t n_q;
    const double* nP;
    double atol, area_P, whole_value, whole_err;
    bool shortcuts;
    const PairConstants* k;
};

// status 0: value, err and points are the reference's and the counts what it adds to
// the row's AreaStats; otherwise declined, for the reference to take the whole pair
// (nothing counted): 1 umbras to look for, 2 too many distinct lines (the reference
// raises), 3 the compiled cells not built or not covering P, 4 a blocker in the
// receiver's plane where the pair has solids, 5 no blocker but those in that plane or no
// compiled hidden set-up, 6 the levels declined, 7 the rules' sum to check triangle by
// triangle.
struct PairResult {
    int status = 0;
    double value = 0, err = 0;
    long long points = 0, culled_events = 0, solid_events = 0, curved_events = 0,
              curved_skipped = 0, back_faces = 0, unevaluated = 0;
};

PairResult occluded_pair(const PairArgs& args);

}  // namespace exactff

#endif
