// One edge's term of the sector form and its rounding estimate, shared by the compiled
// sector sums of unoccluded rows (kernel/_sector.cpp) and of the area code's hidden pieces
// (area/_hidden.cpp); the numpy reference is kernel/sector.py's clipped_sector_sums.
//
// The edge runs from A + Ea to A + Eb (A the polygon's reference vertex from the point,
// Ea and Eb offsets from it, in the receiving frame, both ends at or above the horizon).
// Its plane in offset form is m = A x (Eb - Ea) + Ea x Eb, its term theta m_z / |m| with
// theta the angle between the ends' directions, and the term's rounding, first order,
// theta min(2, C2 u (Z + theta^2 |a| |b|) / |m|) with Z the magnitudes of m_z's summands
// (docs/explanation/robustness.md); c2eps is C2 u. A NaN bound is clamped to 2 theta here
// (std::min's rule); a caller that must propagate it tests `rel` itself.

#ifndef EXACTFF_SECTOR_TERM_H
#define EXACTFF_SECTOR_TERM_H

#include <cmath>
#include <limits>

namespace exactff {

template <typename R>
struct SectorTerm {
    R term;   // theta m_z / |m| (0 where |m| = 0)
    R err;    // its rounding estimate
    R rel;    // the estimate's factor before the clamp to 2
};

template <typename R>
inline SectorTerm<R> sector_term(R Ax, R Ay, R Az, R Eax, R Eay, R Eaz, R Ebx, R Eby, R Ebz,
                                 R c2eps) {
    const R Dx = Ebx - Eax, Dy = Eby - Eay, Dz = Ebz - Eaz;
    const R p1 = Ax * Dy, p2 = Ay * Dx, p3 = Eax * Eby, p4 = Eay * Ebx;
    const R Mz = (p1 - p2) + (p3 - p4);
    const R Mx = (Ay * Dz - Az * Dy) + (Eay * Ebz - Eaz * Eby);
    const R My = (Az * Dx - Ax * Dz) + (Eaz * Ebx - Eax * Ebz);
    const R s = std::sqrt(Mx * Mx + My * My + Mz * Mz);
    const R ax = Ax + Eax, ay = Ay + Eay, az = Az + Eaz;
    const R bx = Ax + Ebx, by = Ay + Eby, bz = Az + Ebz;
    const R theta = std::atan2(s, ax * bx + ay * by + az * bz);
    const bool ok = s > 0;
    SectorTerm<R> out;
    out.term = ok ? theta * Mz / s : R(0);
    const R Z = std::fabs(p1) + std::fabs(p2) + std::fabs(p3) + std::fabs(p4);
    const R Nm = std::sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz));
    out.rel = ok ? c2eps * (Z + theta * theta * Nm) / s
                 : (Nm > 0 ? std::numeric_limits<R>::infinity() : R(0));
    out.err = theta * (out.rel < 2 ? out.rel : R(2));
    return out;
}

}  // namespace exactff

#endif
