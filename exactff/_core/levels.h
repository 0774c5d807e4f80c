// The adaptive levels of an occluded pair's hidden-part integral, compiled (the area
// code's per-pair loop, exactff/area/adaptive.py, _adaptive_levels, which stays the
// reference; docs/explanation/area-form-factors.md): level by level, the triangles'
// pairs of rules (rules.py), the hidden part at their nodes (hidden.h, with hidden.py's
// estimate), the unoccluded point values there (sector_sums.h, points.py), the rules'
// differences summed over the pair against half of the tolerance, and the triangles of
// the largest differences refined while the sum exceeds it (a global budget,
// rules.py's budget_refined), until the rest is accepted. Where a point's hidden part
// cannot be trusted (lost: hidden.py sends it to the bound or the engine) or a value is
// below 0 beyond its estimate, nothing is returned but the status, and the caller takes
// the whole call the reference's way.

#ifndef EXACTFF_CORE_LEVELS_H
#define EXACTFF_CORE_LEVELS_H

#include <cstdint>
#include <vector>

#include "hidden.h"

namespace exactff {

// The levels' rules, in LevelArgs::rules' order (compiled_pair.py's LEVEL_RULES).
constexpr int kLevelRules = 11;

// A quadrature rule on the triangle: collapsed (Duffy) Gauss-Legendre with n points a side
// (nodes and weights on [-1, 1]), or fully symmetric (barycentric points (m, 3) and
// weights summing to 1).
struct TriangleRule {
    bool collapsed = true;
    std::vector<double> x, w;   // collapsed: the 1-D rule; symmetric: x (m, 3), w (m,)
};

// Arguments: T (t, 3, 3) the triangles, depth, rung (0: lower pair, 1: higher pair) and
// corner (first vertex where a blocker touches the emitter) per triangle; nP (3,) the
// emitter's unit normal, frame (3, 3) its receiving frame; area_P, total_area (of the
// cells), atol the pair's absolute tolerance, start the rung a quarter starts on,
// rules_err the rules' differences accepted before this call; rules: symmetric degree 4
// and 8, collapsed 3 and 5 (rung 0 at a corner or at a fine tolerance), 6 and 10 (rung
// 1), 4 (the third rule at a corner on rung 0), and symmetric degree 2 and 4; symmetric:
// rung 0 off a corner takes the symmetric pair of degrees 4 and 8 (atol >=
// AREA_LOW_RULES_TOLERANCE), and a small triangle off a corner (at most small_share of
// P's area, its box's diagonal at most small_reach times its box's distance to the
// boxes of Qc and the blockers' pieces) the pair of degrees 2 and 4 on rung 0 and of 4
// and 8 on rung 1 (rules.py's rule_pair, far_triangles); the last two rules, weights on
// the 22 nodes of the symmetric rules of degree 4 and 8 together, the null rules of
// degree 5 whose spread, times null_factor, the symmetric pair of degree 4 and 8 takes
// as its difference where larger (rules.py's symmetric_null_spread). Qc (q, 3) the
// receiver's part; the hidden set-up (hidden.py's HiddenSetup) in hidden (its X and n
// unset, its back_face, edge_on and precise_atol set per chunk from the factors here),
// lo, hi (3,) its box, and lines, the clipping lines' count of the estimate; the
// tolerances by name.
struct LevelArgs {
    std::vector<double> T;
    std::vector<long long> depth, rung;
    std::vector<unsigned char> corner;
    const double *nP, *frame;
    double area_P, total_area, atol, rules_err;
    long long start;
    // sym4, sym8, gl3, gl5, gl6, gl10, gl4, sym2, sym4, and the two null rules
    const TriangleRule* rules[kLevelRules];
    bool symmetric;
    const double* Qc;
    std::int64_t n_q;
    HiddenArgs hidden;
    const double *lo, *hi;
    double lines;
    // AREA_SLIVER_SHARE, AREA_IMAGE_BUDGET_SHARE, AREA_BACK_FACE_RTOL, AREA_EDGE_ON_RTOL,
    // AREA_IMAGE_PRECISE_SHARE, AREA_BOOLEAN_ULPS, AREA_IMAGE_RTOL, EPS, C1, C2,
    // OFFSET_ROUNDING_ULPS, AREA_SMALL_TRIANGLE_SHARE, AREA_SMALL_TRIANGLE_REACH,
    // AREA_NULL_RULE_FACTOR, AREA_MAX_DEPTH, AREA_POINTS_PER_CALL
    double sliver_share, budget_share, back_face_rtol, edge_on_rtol, precise_share,
        boolean_ulps, image_rtol, eps, c1, c2, offset_ulps, small_share, small_reach,
        null_factor;
    long long max_depth, points_per_call;
};

// The triangles accepted, in the order accepted (per triangle: vertices, level, rung,
// corner, and per unit area of P the high rule's integral of the hidden part, the low
// rule's, the rules' difference, the nodes' estimates, the two rules' integrals of the
// unoccluded point values and their estimates), the slivers' area, the points evaluated
// and the back faces skipped; ok false: a point lost, a value below 0 beyond its
// estimate or a rules' difference not finite (the rest then empty).
struct LevelResult {
    bool ok = true;
    std::vector<double> T, hi, lo, diff, rnd, hiU, loU, rndU;
    std::vector<long long> depth, rung;
    std::vector<unsigned char> corner;
    double slivers = 0;
    long long points = 0, back_faces = 0;
};

LevelResult adaptive_levels(const LevelArgs& args);

// The cells' triangles T (t, 3, 3) each with first a vertex where a blocker's vertex (Vb
// (m, 3)) touches the emitter's plane n . x = dP (adaptive.py's _corner_first, the
// reference): a vertex within hull_rtol of the triangle's size of Vb's vertex, or within
// reach of it, with that vertex within hull_rtol of the size of the plane; a triangle
// with two or three such vertices cut in four first (after the others, in order). Returns
// the triangles and per triangle whether its first vertex is such a corner.
void corner_first(std::vector<double>& T, const double* Vb, std::int64_t m, const double* n,
                  double dP, double reach, double hull_rtol, std::vector<unsigned char>& corner);

}  // namespace exactff

#endif
