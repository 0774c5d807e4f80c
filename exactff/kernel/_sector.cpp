// The sector sums of an unoccluded row in one compiled pass (exactff/kernel/point.py,
// unoccluded_row; exactff/kernel/ladder.py, extended_values): for each polygon of a list,
// its vertices taken to the receiver's local frame in offset form, clipped to the upper
// half-space, and the sector form's sum (DESIGN 2.1) with its rounding model (DESIGN 2.2)
// and the offsets' rounding. The same arithmetic, in the same order, as
// kernel/sector.py's clipped_sector_sums(..., rounded_offsets=True) and _offset_rounding,
// which stay the reference (tests/test_unoccluded_compiled.py compares them); templated
// on the working type: double for the first tier, long double for the second (on x86 64
// bits of mantissa).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "_sector_term.h"

namespace py = pybind11;

namespace {

template <typename R>
struct V3 {
    R x, y, z;
};

template <typename R>
inline R norm3(R x, R y, R z) { return std::sqrt(x * x + y * y + z * z); }

// a vertex in offset form and what the edges on either side of it share: its offset E
// from the polygon's first vertex, its position a = A + E from the point, |a|, and
// |E| + |A| (the scale of its rounding)
template <typename R>
struct Vx {
    V3<R> e, a;
    R la, size;
};

// per polygon: its sum of sector terms, the sum of their magnitudes, the terms' rounding
// estimate plus the offsets' (kernel/sector.py, clipped_sector_sums and _offset_rounding)
// (the constants as kernel/sector.py has them: Python floats, rounded to double, then
// converted to R)
template <typename R>
void polygon_sums(const V3<R>& A, const std::vector<Vx<R>>& E, double eps, double ulps,
                  double c2eps_, R* sum, R* mag, R* errs) {
    const size_t K = E.size();
    const double pi_d = 3.14159265358979323846;
    const R half_pi = static_cast<R>(pi_d / 2), four_pi = static_cast<R>(4 * pi_d);
    // gamma_8 of the offsets' rounding, and the slack of the span's cosines
    const R g = static_cast<R>(ulps * eps / (1 - ulps * eps));
    const R slack = static_cast<R>(ulps * eps);
    const R c2eps = static_cast<R>(c2eps_);
    R S = 0, M = 0, Er = 0;
    bool have_first = false;
    R fx = 0, fy = 0;   // the polygon's first horizon crossing (x, y)
    for (size_t i = 0; i < K; ++i) {
        const size_t j = i + 1 == K ? 0 : i + 1;
        V3<R> Ea = E[i].e, Eb = E[j].e;
        // _offset_rounding: what the offsets' rounding can move this edge's term
        R moved;
        {
            const R size_a = E[i].size, size_b = E[j].size;
            const R eta = g * (size_a >= size_b ? size_a : size_b);
            const V3<R>& a = E[i].a;
            const V3<R>& b = E[j].a;
            const V3<R> d{b.x - a.x, b.y - a.y, b.z - a.z};
            const R la = E[i].la, lb = E[j].la, ld = norm3(d.x, d.y, d.z);
            const R cx = a.y * b.z - a.z * b.y, cy = a.z * b.x - a.x * b.z,
                    cz = a.x * b.y - a.y * b.x;
            const R h = norm3(cx, cy, cz) / ld;
            R span = std::fabs((d.x * b.x + d.y * b.y + d.z * b.z) / (ld * lb) -
                               (d.x * a.x + d.y * a.y + d.z * a.z) / (ld * la)) +
                     slack;
            if (!(span <= 2)) span = span > 2 ? R(2) : span;
            const R turn = eta <= R(0.1) * h ? R(1.01) : half_pi;
            moved = h > eta ? 2 * eta * turn * span / h : four_pi;
            if (!std::isfinite(moved)) moved = four_pi;
            if (moved > four_pi) moved = four_pi;
            const R top = a.z >= b.z ? a.z : b.z;
            if (!(top + eta >= 0 && ld > 0)) moved = 0;
        }
        const R za = A.z + Ea.z, zb = A.z + Eb.z;
        const bool above_a = za > 0, above_b = zb > 0;
        R phi_term = 0;
        if (above_a != above_b) {
            // horizon crossing of the edge, as an offset (its height is exactly 0)
            const R t = za / (za - zb);
            const V3<R> EX{Ea.x + t * (Eb.x - Ea.x), Ea.y + t * (Eb.y - Ea.y),
                           Ea.z + t * (Eb.z - Ea.z)};
            const R Xx = A.x + EX.x, Xy = A.y + EX.y;
            if (!have_first) {
                have_first = true;
                fx = Xx;
                fy = Xy;
            }
            // the horizon arcs' term: the signed angle from the first crossing
            const R phi = std::atan2(fx * Xy - fy * Xx, fx * Xx + fy * Xy);
            const bool enter = !above_a;
            phi_term = enter ? phi : -phi;
            if (enter) Ea = EX;
            else Eb = EX;
        }
        R term = 0, err = 0;
        if (above_a || above_b) {
            // the edge's term and its rounding (kernel/_sector_term.h)
            const exactff::SectorTerm<R> st = exactff::sector_term(
                A.x, A.y, A.z, Ea.x, Ea.y, Ea.z, Eb.x, Eb.y, Eb.z, c2eps);
            term = st.term;
            err = st.err;
            if (std::isnan(st.rel)) err = st.rel;   // as numpy's minimum propagates NaN
        }
        term += phi_term;
        S += term;
        M += std::fabs(term);
        Er += err + moved;
    }
    *sum = S;
    *mag = M;
    *errs = Er;
}

// Pair k: polygon ids[k] from point P[rows[k]] in frame Rm[rows[k]] (rows of the frame:
// the local axes, geometry.receiver_frame), the pairs of one row or of many.
template <typename R>
py::tuple row_sums(py::array_t<double, py::array::c_style | py::array::forcecast> V_,
                   py::array_t<int64_t, py::array::c_style | py::array::forcecast> offsets_,
                   py::array_t<int64_t, py::array::c_style | py::array::forcecast> ids_,
                   py::array_t<int64_t, py::array::c_style | py::array::forcecast> rows_,
                   py::array_t<double, py::array::c_style | py::array::forcecast> P_,
                   py::array_t<R, py::array::c_style | py::array::forcecast> R_, double eps_,
                   double ulps_, double c2eps_) {
    const double* V = V_.data();
    const int64_t* off = offsets_.data();
    const int64_t* ids = ids_.data();
    const int64_t* rows = rows_.data();
    const double* Pd = P_.data();
    const R* Rall = R_.data();
    const int64_t n = ids_.size();
    const int64_t npoly = offsets_.size() - 1;
    const int64_t nrows = P_.size() / 3;
    if (V_.ndim() != 2 || V_.shape(1) != 3 || P_.size() != 3 * nrows ||
        R_.size() != 9 * nrows || rows_.size() != n)
        throw std::invalid_argument(
            "row_sums: V (N, 3), ids (K,), rows (K,), P (M, 3), R (M, 3, 3) expected");
    for (int64_t k = 0; k < n; ++k) {
        if (ids[k] < 0 || ids[k] >= npoly || off[ids[k]] >= off[ids[k] + 1] ||
            off[ids[k] + 1] > V_.shape(0))
            throw std::out_of_range("row_sums: polygon id out of range or empty");
        if (rows[k] < 0 || rows[k] >= nrows) throw std::out_of_range("row_sums: row out of range");
    }
    py::array_t<R> S_(n), M_(n), E_(n);
    py::array_t<bool> up_(n);
    R* S = S_.mutable_data();
    R* M = M_.mutable_data();
    R* Er = E_.mutable_data();
    bool* up = up_.mutable_data();
    {
        py::gil_scoped_release release;
        std::vector<Vx<R>> E;
        for (int64_t k = 0; k < n; ++k) {
            const int64_t i = ids[k];
            const double* pd = Pd + 3 * rows[k];
            const R* Rm = Rall + 9 * rows[k];
            const R p[3] = {static_cast<R>(pd[0]), static_cast<R>(pd[1]), static_cast<R>(pd[2])};
            const int64_t a = off[i], b = off[i + 1];
            const double* f = V + 3 * a;
            // geometry.rotate of (first - p) and of (vertex - first), in R
            const R fx = static_cast<R>(f[0]), fy = static_cast<R>(f[1]),
                    fz = static_cast<R>(f[2]);
            const R dx = fx - p[0], dy = fy - p[1], dz = fz - p[2];
            const V3<R> A{dx * Rm[0] + dy * Rm[1] + dz * Rm[2],
                          dx * Rm[3] + dy * Rm[4] + dz * Rm[5],
                          dx * Rm[6] + dy * Rm[7] + dz * Rm[8]};
            E.resize(static_cast<size_t>(b - a));
            const R lA = norm3(A.x, A.y, A.z);
            bool above = false;
            for (int64_t v = a; v < b; ++v) {
                const R ex = static_cast<R>(V[3 * v]) - fx,
                        ey = static_cast<R>(V[3 * v + 1]) - fy,
                        ez = static_cast<R>(V[3 * v + 2]) - fz;
                Vx<R>& u = E[static_cast<size_t>(v - a)];
                u.e = {ex * Rm[0] + ey * Rm[1] + ez * Rm[2], ex * Rm[3] + ey * Rm[4] + ez * Rm[5],
                       ex * Rm[6] + ey * Rm[7] + ez * Rm[8]};
                u.a = {A.x + u.e.x, A.y + u.e.y, A.z + u.e.z};
                u.la = norm3(u.a.x, u.a.y, u.a.z);
                u.size = norm3(u.e.x, u.e.y, u.e.z) + lA;
                above |= u.a.z > 0;
            }
            up[k] = above;   // wholly below the horizon: the caller culls it
            polygon_sums(A, E, eps_, ulps_, c2eps_, S + k, M + k, Er + k);
        }
    }
    return py::make_tuple(S_, M_, E_, up_);
}

}  // namespace

PYBIND11_MODULE(_sector, m) {
    m.doc() = "Sector sums of unoccluded rows (exactff.kernel.point.unoccluded_rows)";
    m.def("row_sums", &row_sums<double>,
          "row_sums(V, offsets, ids, rows, P, R, eps, ulps, c2eps) -> (S, mags, errs, above): "
          "polygon ids[k] from P[rows[k]] in the frame R[rows[k]], double precision");
    m.def("row_sums_extended", &row_sums<long double>,
          "the same in long double (R a longdouble frame)");
}
