// The unoccluded area pair in closed form (exactff/area/closed_form.py,
// edge_integrals.py): the edge-pair integral J = int_0^1 int_0^1 ln |a + s e - b - t f|
// ds dt of the Mitalas-Stephenson contour form of Eq. 1, by dilogarithms for skew edges
// and elementary functions for parallel ones, with the magnitude of its terms (its
// rounding scale); and a row's pairs summed, A_P F = (1 / 2 pi) sum (e . f) J, with their
// rounding estimates. The derivation is in edge_integrals.py's notes; the expressions
// here follow its numpy code operation by operation.

#ifndef EXACTFF_CORE_CLOSED_FORM_H
#define EXACTFF_CORE_CLOSED_FORM_H

#include <cstdint>
#include <vector>

namespace exactff {
namespace area {

// the constants of the closed form (exactff._tolerances), passed in by the caller
struct ClosedFormConstants {
    double thin;   // AREA_CLOSED_THIN: a triangle thinner than this share of its size is dropped
    double tiny;   // DOUBLE_TINY: the smallest normal double (|1 + z| floored there)
    double ulps;   // AREA_CLOSED_ULPS: the rounding, in units of eps of the magnitudes
    double eps;    // EPS, the unit roundoff of doubles
    double near;   // AREA_CLOSED_NEAR_PARALLEL: edges within this sine of parallel also
                   // take the parallel form, with the bound of the turn
};

// J and its terms' magnitude M (at least |J|) of n edge pairs (a, e, b, f: (n, 3) each)
void edge_log_integrals(const double* a, const double* e, const double* b, const double* f,
                        std::int64_t n, const ClosedFormConstants& k, double* J, double* M);

// The edge pairs of a row's pairs and their sums: pair p has the emitter part
// VP[po[p] .. po[p+1]) and the receiver part VQ[qo[p] .. qo[p+1]) (rings, (., 3)), scaled
// by inv[p] (1 / L, a power of 2), its sum divided by scale[p] (2 pi A_P / L^2). Every
// edge pair (P's edge outer, Q's inner) whose scaled e . f is not 0 is kept, with its
// owner, its edges' first vertices (ip into VP, iq into VQ), e . f, J and its rounding
// c = ulps eps |e . f| M / scale.
struct RowPairs {
    std::vector<double> value, estimate;           // per pair
    std::vector<std::int64_t> owner, ip, iq;       // per kept edge pair
    std::vector<double> ef, J, c;
};

RowPairs row_pairs(const double* VP, const std::int64_t* po, const double* VQ,
                   const std::int64_t* qo, std::int64_t pairs, const double* inv,
                   const double* scale, const ClosedFormConstants& k);

}  // namespace area
}  // namespace exactff

#endif
