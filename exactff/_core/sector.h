// The sector form of a polygon's point form factor (Lambert's, in the offset form of
// docs/explanation/robustness.md) and its rounding-error model, written once for the
// compiled code: the visibility core's pieces (integrate.cpp, long double and quadruple
// precision), the area rows' hidden pieces (hidden.cpp) and the unoccluded rows' sector
// sums (sector_sums.h). The numpy reference is kernel/sector.py's clipped_sector_sums.
//
// The error model (C1, C2 of exactff._tolerances): an edge's term theta m_z / |m| is
// rounded within theta min(2, C2 u (Z + theta^2 |a| |b|) / |m|), Z the magnitudes of
// m_z's summands, and the sum of the terms within C1 u times the sum of their
// magnitudes; u is the working precision's unit roundoff.

#ifndef EXACTFF_CORE_SECTOR_H
#define EXACTFF_CORE_SECTOR_H

#include <cmath>
#include <limits>

namespace exactff {

// an edge term's relative rounding estimate, C2 u (Z + theta^2 |a| |b|) / |m|, with
// c2eps = C2 u and t2n = theta^2 |a| |b| as the caller forms it
template <typename T>
inline T term_rel(T c2eps, T Z, T t2n, T mnorm) { return c2eps * (Z + t2n) / mnorm; }

// the edge term's rounding: theta min(2, rel) (a NaN rel gives 2 theta, as std::min)
template <typename T>
inline T term_err(T theta, T rel) { return theta * (rel < 2 ? rel : T(2)); }

// the rounding of a sector sum (before the division by 2 pi): C1 u sum |terms| plus the
// terms' own, with c1eps = C1 u
template <typename T>
inline T sum_rounding(T c1eps, T mag, T errs) { return c1eps * mag + errs; }

template <typename T>
struct SectorTerm {
    T term;   // theta m_z / |m| (0 where |m| = 0)
    T err;    // its rounding estimate
    T rel;    // the estimate's factor before the clamp to 2
};

// One edge's term of the sector form and its rounding estimate, in the receiving frame
// (z along the normal). The edge runs from A + Ea to A + Eb (A the polygon's reference
// vertex from the point, Ea and Eb offsets from it, both ends at or above the horizon).
// Its plane in offset form is m = A x (Eb - Ea) + Ea x Eb, its term theta m_z / |m| with
// theta the angle between the ends' directions. A degenerate edge (|m| = 0) of nonzero
// length has an infinite rel; a caller that must propagate a NaN rel tests it itself.
template <typename T>
inline SectorTerm<T> sector_term(T Ax, T Ay, T Az, T Eax, T Eay, T Eaz, T Ebx, T Eby, T Ebz,
                                 T c2eps) {
    const T Dx = Ebx - Eax, Dy = Eby - Eay, Dz = Ebz - Eaz;
    const T p1 = Ax * Dy, p2 = Ay * Dx, p3 = Eax * Eby, p4 = Eay * Ebx;
    const T Mz = (p1 - p2) + (p3 - p4);
    const T Mx = (Ay * Dz - Az * Dy) + (Eay * Ebz - Eaz * Eby);
    const T My = (Az * Dx - Ax * Dz) + (Eaz * Ebx - Eax * Ebz);
    const T s = std::sqrt(Mx * Mx + My * My + Mz * Mz);
    const T ax = Ax + Eax, ay = Ay + Eay, az = Az + Eaz;
    const T bx = Ax + Ebx, by = Ay + Eby, bz = Az + Ebz;
    const T theta = std::atan2(s, ax * bx + ay * by + az * bz);
    const bool ok = s > 0;
    SectorTerm<T> out;
    out.term = ok ? theta * Mz / s : T(0);
    const T Z = std::fabs(p1) + std::fabs(p2) + std::fabs(p3) + std::fabs(p4);
    const T Nm = std::sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz));
    out.rel = ok ? term_rel(c2eps, Z, theta * theta * Nm, s)
                 : (Nm > 0 ? std::numeric_limits<T>::infinity() : T(0));
    out.err = term_err(theta, out.rel);
    return out;
}

}  // namespace exactff

#endif
