// The unoccluded area pair in closed form (closed_form.h): the edge-pair integrals and a
// row's sums. Each expression follows exactff/area/edge_integrals.py (and the edge-pair
// loop of closed_form.unoccluded_pairs), in the same order of operations; the
// dilogarithm is dilog.h's.

#include "closed_form.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "dilog.h"
#include "vec.h"

namespace exactff {
namespace area {

namespace {

using V = Vec3<double>;

inline V load(const double* p) { return {p[0], p[1], p[2]}; }
inline V add3(const V& a, const V& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V scaled(const V& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline V over(const V& a, double s) { return {a.x / s, a.y / s, a.z / s}; }

// skew edges (e x f != 0; exactff/area/edge_integrals.py's notes). The parallelogram
// w + s e - t f (w: the part of a - b in the plane of e and f, at distance d from it),
// cut into triangles from the origin to its edges, each of height h over its edge and
// positions t along it: T = (1/4) [h Phi(t) - h t + d^2 K(phi)] between the ends, with
// Phi(t) = t ln(t^2 + m^2) - 2 t + 2 m atan(t / m), m^2 = h^2 + d^2, and
// K(phi) = -phi ln rho - Im Li2(-rho e^{2 i phi}) + Im Li2(-e^{2 i phi}), rho = q^2.
void skew(const V& a, const V& e, const V& b, const V& f, const ClosedFormConstants& k,
          double& J, double& M) {
    const V c = cross(e, f);
    const double cn = std::sqrt(dot(c, c));
    const V n = over(c, cn);
    const V w = sub(a, b);
    const double d = dot(w, n);
    const V wp = sub(w, scaled(n, d));
    const double d2 = d * d;
    const V we = add3(wp, e);
    const V corners[4] = {wp, we, sub(we, f), sub(wp, f)};
    double S = 0.0, Mag = 0.0;
    for (int i = 0; i < 4; ++i) {
        const V& A = corners[i];
        const V D = sub(corners[(i + 1) % 4], A);
        const double L = std::sqrt(dot(D, D));
        // a side of no length (e or f lost to rounding next to w): its triangle has no
        // area (and the other sides' magnitudes, of |w| |e| or |w| |f|, cover what it
        // lost)
        if (!(L > 0)) continue;
        const V u = over(D, L);
        const double tA = dot(A, u);
        const double tB = tA + L;
        const double hs = dot(cross(A, u), n);   // signed: the triangle's side
        const double absA = std::sqrt(dot(A, A));
        const double h = std::fabs(hs) > k.thin * (absA + L) ? std::fabs(hs) : 0.0;
        const double m2 = h * h + d2;
        const double m = std::sqrt(m2);
        const double mh = m + h;
        const double q = mh > 0 ? std::fabs(d) / mh : 0.0;        // sqrt(rho)
        const double lq = q > 0 ? std::log(q) : 0.0;
        // h and t carry the rounding of the corner A: the elementary part's magnitude
        // with h + |A| + L for h
        const double H = h + absA + L;
        double tri = -h * L, mag = H * L;
        const bool live = h > 0;
        for (int side = 0; side < 2; ++side) {
            const double t = side == 0 ? tB : tA;
            const double sgn = side == 0 ? 1.0 : -1.0;
            // Phi(t), the elementary part (a logarithm's rounding is absolute)
            const double tt = t * t + m2;
            const double lg = std::log(tt > 0 ? tt : 1.0);
            const double p1 = t * lg, p2 = 2.0 * m * std::atan2(t, m);
            tri = tri + sgn * h * (p1 - 2.0 * t + p2);
            mag = mag + H * (std::fabs(t) * (std::fabs(lg) + 4.0) + std::fabs(p2) + 2.0 * m);
            if (!live) continue;
            // K(phi): e^{2 i phi} = ((h^2 - t^2) + 2 i h t) / (h^2 + t^2), h and t scaled
            // by the larger
            double sc = std::max(h, std::fabs(t));
            sc = sc > 0 ? sc : 1.0;
            const double hn = h / sc, tn = t / sc;
            const double den = hn * hn + tn * tn;
            const double zr = (hn * hn - tn * tn) / den, zi = (2.0 * hn * tn) / den;
            const double phi = std::atan2(t, h);
            const double k1 = -2.0 * phi * lq;
            const double r = -(q * q);
            const double k2 = -li2({r * zr, r * zi}).imag();     // -Im Li2(-rho e^{2 i phi})
            const double k3 = li2({-zr, -zi}).imag();            // Im Li2(-e^{2 i phi})
            tri = tri + sgn * d2 * (k1 + k2 + k3);
            // the dilogarithms' rounding: of their values, and of their arguments times
            // the derivative, ln |1 - w| / |w| (logarithmic near w = 1)
            const double dl =
                std::fabs(std::log(std::max(std::hypot(1.0 + (q * q) * zr, (q * q) * zi), k.tiny))) +
                std::fabs(std::log(std::max(std::hypot(1.0 + zr, zi), k.tiny)));
            const double km = 2.0 * std::fabs(phi) * (std::fabs(lq) + 2.0) + std::fabs(k2) +
                              std::fabs(k3) + dl + 4.0;
            mag = mag + d2 * km;
        }
        // an edge through the origin (h = 0) bounds a triangle of no area
        if (live) S += (hs > 0 ? 1.0 : -1.0) * tri;
        Mag += mag;
    }
    // the parallelogram w + s e - t f is traversed clockwise about n
    J = -0.25 * S / cn;
    M = 0.25 * Mag / cn;
}

// parallel edges (e x f = 0, or nearly: edge_log_integral takes this form too within
// AREA_CLOSED_NEAR_PARALLEL, with the turn's bound), the double
// antiderivative G2(z) = (1/4) (z^2 - delta^2) ln(z^2 + delta^2) - (3/4) z^2
// + delta z atan(z / delta) at the four corners
void parallel(const V& a, const V& e, const V& b, const V& f, double& J, double& M) {
    const double X = std::sqrt(dot(e, e));
    const V u = over(e, X);
    const double Y = dot(f, u);                     // sigma |f|
    const V w = sub(a, b);
    const double z0 = dot(w, u);
    const V perp = sub(w, scaled(u, z0));
    const double delta = std::sqrt(dot(perp, perp));
    const double dd = delta * delta;
    const double zs[4] = {z0 + X, z0, (z0 + X) - Y, z0 - Y};
    const double sg[4] = {1.0, -1.0, -1.0, 1.0};
    double Js = 0.0, Ms = 0.0;
    for (int i = 0; i < 4; ++i) {
        const double z = zs[i], zz = z * z;
        const double x = zz - dd, y = zz + dd;
        const double g1 = 0.25 * (x == 0 ? 0.0 : x * std::log(y));     // xlogy
        const double g3 = delta > 0 ? delta * z * std::atan2(z, delta) : 0.0;
        Js += sg[i] * (g1 - 0.75 * zz + g3);
        // a logarithm's rounding is absolute: (z^2 - delta^2) ln(...) is off by
        // |z^2 - delta^2| ulps
        const double lg = std::log(y > 0 ? y : 1.0);
        Ms += 0.25 * std::fabs(x) * (std::fabs(lg) + 4.0) + zz + std::fabs(g3) + dd;
    }
    J = Js / (X * Y);
    M = Ms / std::fabs(X * Y);
}

// x y' - x' y to within 1.5 units of its own rounding (Kahan's 2 x 2 determinant, with
// fused multiply-adds): 0 only where it is 0, however near parallel the rows
inline double det2(double x, double y, double xp, double yp) {
    const double w = xp * y;
    const double err = std::fma(-xp, y, w);      // w - x' y, exactly
    return std::fma(x, yp, -w) + err;
}

// |e x f|, each component to within 1.5 units of its rounding
inline double accurate_cross_norm(const V& e, const V& f) {
    const double cx = det2(e.y, e.z, f.y, f.z), cy = det2(e.z, e.x, f.z, f.x),
                 cz = det2(e.x, e.y, f.x, f.y);
    return std::sqrt(cx * cx + cy * cy + cz * cz);
}

void edge_log_integral(const V& a, const V& e, const V& b, const V& f,
                       const ClosedFormConstants& k, double& J, double& M) {
    const V c = cross(e, f);
    const double cc = dot(c, c), ee = dot(e, e), ff = dot(f, f);
    if (!(cc <= k.near * k.near * ee * ff)) {
        skew(a, e, b, f, k, J, M);
        M = std::max(M, std::fabs(J));
        return;
    }
    // within a sine of k.near of parallel (or parallel): the skew form's terms grow as
    // 1 / sin (the lines' nearest points recede as 1 / sin, its triangles with them: at
    // a sine of 3e-17, edges parallel but for their vertices' rounding, terms of 1e18
    // and no digit left). The parallel form about the longer edge (J is symmetric in
    // the two edges) takes the shorter turned onto its direction, each point of it
    // moved by at most delta = |e x f| / F (F the longer's length); ln r then moves by
    // at most ln(1 + delta / min(r, r')), and as the (s, t) where r < x measure at most
    // 2 x / F (a chord of a ball of radius x along either edge), its integral, twice
    // (r and r'), is at most 4 (delta / F) (1 + ln(1 + F / (2 delta))): added to the
    // parallel form's magnitude (in units of its rounding), and the smaller of the two
    // forms' estimates kept
    const double cn = accurate_cross_norm(e, f);
    double Jp, Mp;
    if (ee >= ff)
        parallel(a, e, b, f, Jp, Mp);
    else
        parallel(b, f, a, e, Jp, Mp);
    Mp = std::max(Mp, std::fabs(Jp));
    if (cn > 0) {
        // delta / F, rounded up by its few roundings (cn within 2 of them: Kahan's
        // determinants with an FMA; the squared lengths within 3; the square root and
        // the division; 16 covers them all with room)
        const double q = (1.0 + 16.0 * k.eps) * cn / std::max(ee, ff);
        Mp += 4.0 * q * (1.0 + std::log1p(0.5 / q)) / (k.ulps * k.eps);
    }
    // the skew form where both cross products are nonzero (the plain one, which it
    // divides by, may round to 0 for edges not quite parallel)
    if (cn > 0 && cc > 0) {
        skew(a, e, b, f, k, J, M);
        M = std::max(M, std::fabs(J));
        if (M <= Mp) return;
    }
    J = Jp;
    M = Mp;
}

}  // namespace

void edge_log_integrals(const double* a, const double* e, const double* b, const double* f,
                        std::int64_t n, const ClosedFormConstants& k, double* J, double* M) {
    for (std::int64_t i = 0; i < n; ++i)
        edge_log_integral(load(a + 3 * i), load(e + 3 * i), load(b + 3 * i), load(f + 3 * i), k,
                          J[i], M[i]);
}

RowPairs row_pairs(const double* VP, const std::int64_t* po, const double* VQ,
                   const std::int64_t* qo, std::int64_t pairs, const double* inv,
                   const double* scale, const ClosedFormConstants& k) {
    RowPairs out;
    out.value.assign(pairs, 0.0);
    out.estimate.assign(pairs, 0.0);
    const double unit = k.ulps * k.eps;
    const V zero = {0.0, 0.0, 0.0};
    for (std::int64_t p = 0; p < pairs; ++p) {
        const std::int64_t p0 = po[p], p1 = po[p + 1], q0 = qo[p], q1 = qo[p + 1];
        const double s = inv[p];
        for (std::int64_t i = p0; i < p1; ++i) {
            const std::int64_t inext = i + 1 < p1 ? i + 1 : p0;
            const V a = load(VP + 3 * i);
            const V e = scaled(sub(load(VP + 3 * inext), a), s);
            for (std::int64_t j = q0; j < q1; ++j) {
                const std::int64_t jnext = j + 1 < q1 ? j + 1 : q0;
                const V b = load(VQ + 3 * j);
                const V f = scaled(sub(load(VQ + 3 * jnext), b), s);
                const double ef = dot(e, f);
                if (ef == 0) continue;                 // perpendicular edges: no term
                const V w = scaled(sub(a, b), s);
                double J, M;
                edge_log_integral(w, e, zero, f, k, J, M);
                const double c = unit * std::fabs(ef) * M / scale[p];
                out.value[p] += ef * J / scale[p];
                out.estimate[p] += c;
                out.owner.push_back(p);
                out.ip.push_back(i);
                out.iq.push_back(j);
                out.ef.push_back(ef);
                out.J.push_back(J);
                out.c.push_back(c);
            }
        }
    }
    return out;
}

}  // namespace area
}  // namespace exactff
