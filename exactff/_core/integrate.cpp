// A visible piece's sector sum in the visibility core, in long double (integrate) and in
// quadruple precision (integrate_quad), with the error model of sector.h; or the
// paper's Eq. 3 in its stable form, a row's choice.

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "constants.h"
#include "core.h"
#include "sector.h"

namespace exactff {

// the sector form of one convex piece above the horizon, in offset form (as
// exactff.kernel.clipped_sector_sums): each edge's plane as
// m = a0 x (e_b - e_a) + e_a x e_b with a0 the first vertex's direction and e the
// world offsets from it, accurate for pieces small next to their distance; each
// term's rounding bounded by the magnitudes of the products in n . m (C2 ulps per
// unit of the cross product's condition), the sum's by C1 ulps of its terms
//
// With `eq3` (its frame e1, e2 with e1 x e2 = n), each edge is integrated by the
// paper's Eq. 3 (corrected) over its monotone spans, in its stable form
// (tools/derive_eq3.py, exactff.kernel.eq3_ring_sums): minus twice int y dx along
// the arc's image is C theta - sin(theta) (v_x u_y + u_x v_y), the sector term and
// d(x y)/dt at the arc's midpoint u (v = m x u / |m|) times sin(theta), every term
// O(theta); the second term's rounding is the plane's (as the first's) and a few
// roundoffs of the unit midpoint and tangent, times 2 sin(theta / 2)
void Core::integrate(const Piece& q, int64_t f, const V3& n, R* value, R* bound,
                     const RowStats* eq3) const {
    R S = 0, mag = 0, errs = 0;
    const size_t m = q.size();
    const V3 a0 = q[0].v;
    R unused;
    auto offset = [&](const Vertex& u) { return between(q[0], u, f, &unused); };
    // each vertex's offset formed once: an edge's end is the next edge's start
    const V3 first = offset(q[0]);
    V3 next = first;
    for (size_t i = 0; i < m; ++i) {
        const size_t j = i + 1 == m ? 0 : i + 1;
        const Vertex& a = q[i];
        const Vertex& b = q[j];
        const V3 ea = next, eb = j == 0 ? first : offset(b);
        next = eb;
        const V3 d{eb.x - ea.x, eb.y - ea.y, eb.z - ea.z};
        const V3 c1 = cross(a0, d), c2 = cross(ea, eb);
        const V3 c{c1.x + c2.x, c1.y + c2.y, c1.z + c2.z};
        // the magnitudes of the products that make up n . m
        const R Z = std::fabs(n.x) * (std::fabs(a0.y * d.z) + std::fabs(a0.z * d.y) +
                                      std::fabs(ea.y * eb.z) + std::fabs(ea.z * eb.y)) +
                    std::fabs(n.y) * (std::fabs(a0.z * d.x) + std::fabs(a0.x * d.z) +
                                      std::fabs(ea.z * eb.x) + std::fabs(ea.x * eb.z)) +
                    std::fabs(n.z) * (std::fabs(a0.x * d.y) + std::fabs(a0.y * d.x) +
                                      std::fabs(ea.x * eb.y) + std::fabs(ea.y * eb.x));
        const R cl = norm(c);
        const R Nm = a.length * b.length;
        const R theta = std::atan2(cl, dot(a.v, b.v));
        if (!(cl > 0)) {
            if (Nm > 0) errs += 2 * K_.eps;  // a degenerate edge: its term unknown
            continue;
        }
        const R t = theta * dot(n, c) / cl;
        S += t;
        mag += std::fabs(t);
        const R rel = term_rel(K_.c2 * K_.eps, Z, theta * theta * Nm, cl);
        errs += term_err(theta, rel);
        if (eq3) {
            const R sin_t = cl / Nm;
            const V3 um{a.v.x / a.length + b.v.x / b.length, a.v.y / a.length + b.v.y / b.length,
                        a.v.z / a.length + b.v.z / b.length};
            const R lu = norm(um);
            if (lu > 0) {
                const V3 u{um.x / lu, um.y / lu, um.z / lu};
                const V3 v = cross(c, u);
                const R xy = sin_t * (dot(v, eq3->e1) * dot(u, eq3->e2) +
                                      dot(u, eq3->e1) * dot(v, eq3->e2)) / cl;
                S -= xy;
                mag += std::fabs(xy);
            } else {
                errs += sin_t;  // opposite ends: no midpoint, the factor is within 1
            }
            errs += term_err(theta, rel) +
                    EQ3_FACTOR_ULPS * K_.eps * 2 * std::sin(theta / 2);
        }
    }
    const R two_pi = 6.283185307179586476925286766559L;
    *value = std::fabs(S) / two_pi;
    *bound = sum_rounding(K_.c1 * K_.eps, mag, errs) / two_pi;
}

// the same sector form in quadruple precision, from the directions Core::refine gave
// the piece's vertices (their errors are charged edge by edge, apart), with the
// normal as given (unnormalised: the value is divided by its length at the end, a
// relative error); the second tier for pieces whose terms cancel (grazing, far,
// small, slivers)
//
// With `eq3`, Eq. 3's stable form as in Core::integrate, in a frame (e1, e2, n)
// built here in quadruple precision (the midpoint terms telescope around the ring
// for any frame: only their rounding depends on it)
void Core::integrate_quad(const std::vector<std::array<Quad, 3>>& v, const double* pn, R* value,
                          R* bound, bool eq3) const {
    const size_t m = v.size();
    const Quad n[3] = {pn[0], pn[1], pn[2]};
    const Quad nl = q_sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    Quad S = 0, mag = 0, errs = 0;
    Quad e1[3] = {0, 0, 0}, e2[3] = {0, 0, 0};
    if (eq3) {
        // e1: n crossed with the axis n is least along, e2 = n x e1 (n unit here)
        Quad un[3] = {n[0] / nl, n[1] / nl, n[2] / nl};
        int k = 0;
        for (int j = 1; j < 3; ++j)
            if (q_abs(un[j]) < q_abs(un[k])) k = j;
        Quad ax[3] = {0, 0, 0};
        ax[k] = 1;
        e1[0] = un[1] * ax[2] - un[2] * ax[1];
        e1[1] = un[2] * ax[0] - un[0] * ax[2];
        e1[2] = un[0] * ax[1] - un[1] * ax[0];
        const Quad l1 = q_sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        for (int j = 0; j < 3; ++j) e1[j] /= l1;
        e2[0] = un[1] * e1[2] - un[2] * e1[1];
        e2[1] = un[2] * e1[0] - un[0] * e1[2];
        e2[2] = un[0] * e1[1] - un[1] * e1[0];
    }
    const auto& a0 = v[0];
    // each vertex's length, once (every vertex ends two edges): in long double from
    // the directions rounded to it, for the terms' rounding estimates (within a few
    // roundoffs of long double: nothing next to the estimates' own slack); in quadruple
    // precision for Eq. 3's midpoints, which enter the value
    thread_local std::vector<Quad> lengths;
    thread_local std::vector<R> rough;
    lengths.resize(m);
    rough.resize(m);
    for (size_t i = 0; i < m; ++i) {
        const R x = static_cast<R>(v[i][0]), y = static_cast<R>(v[i][1]),
                z = static_cast<R>(v[i][2]);
        rough[i] = std::sqrt(x * x + y * y + z * z);
        if (eq3) lengths[i] = q_sqrt(v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2]);
    }
    const R nr = static_cast<R>(nl);
    const R nr3[3] = {std::fabs(static_cast<R>(n[0])), std::fabs(static_cast<R>(n[1])),
                      std::fabs(static_cast<R>(n[2]))};
    // each vertex's offset from the first's, and rounded to long double (Z below)
    thread_local std::vector<std::array<Quad, 3>> offs;
    thread_local std::vector<std::array<R, 3>> offr;
    offs.resize(m);
    offr.resize(m);
    for (size_t i = 0; i < m; ++i)
        for (int k = 0; k < 3; ++k) {
            offs[i][k] = v[i][k] - v[0][k];
            offr[i][k] = static_cast<R>(offs[i][k]);
        }
    const R a0r[3] = {static_cast<R>(a0[0]), static_cast<R>(a0[1]), static_cast<R>(a0[2])};
    const R c2eps = static_cast<R>(K_.c2) * static_cast<R>(QUAD_EPS);
    for (size_t i = 0; i < m; ++i) {
        const size_t j = i + 1 == m ? 0 : i + 1;
        const Quad* ea = offs[i].data();
        const Quad* eb = offs[j].data();
        Quad d[3], c[3];
        for (int k = 0; k < 3; ++k) d[k] = eb[k] - ea[k];
        c[0] = (a0[1] * d[2] - a0[2] * d[1]) + (ea[1] * eb[2] - ea[2] * eb[1]);
        c[1] = (a0[2] * d[0] - a0[0] * d[2]) + (ea[2] * eb[0] - ea[0] * eb[2]);
        c[2] = (a0[0] * d[1] - a0[1] * d[0]) + (ea[0] * eb[1] - ea[1] * eb[0]);
        const Quad cl = q_sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        const R rla = rough[i], rlb = rough[j];
        if (!(cl > 0)) {
            if (rla * rlb > 0) errs += 2 * QUAD_EPS;
            continue;
        }
        const Quad ab = v[i][0] * v[j][0] + v[i][1] * v[j][1] + v[i][2] * v[j][2];
        const Quad theta = q_atan2(cl, ab);
        const Quad t = theta * (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / (cl * nl);
        S += t;
        mag += q_abs(t);
        // the term's rounding estimate, in long double from the quadruple operands
        // rounded to it (the magnitudes Z of n . c's products, as the long double sum
        // forms them), raised by 64 roundoffs of long double to hold the quadruple
        // one's
        R Z;
        {
            const R* A = a0r;
            const R* Ea = offr[i].data();
            const R* Eb = offr[j].data();
            const R Dd[3] = {static_cast<R>(d[0]), static_cast<R>(d[1]), static_cast<R>(d[2])};
            const R P[3] = {std::fabs(A[1] * Dd[2]) + std::fabs(A[2] * Dd[1]) +
                                std::fabs(Ea[1] * Eb[2]) + std::fabs(Ea[2] * Eb[1]),
                            std::fabs(A[2] * Dd[0]) + std::fabs(A[0] * Dd[2]) +
                                std::fabs(Ea[2] * Eb[0]) + std::fabs(Ea[0] * Eb[2]),
                            std::fabs(A[0] * Dd[1]) + std::fabs(A[1] * Dd[0]) +
                                std::fabs(Ea[0] * Eb[1]) + std::fabs(Ea[1] * Eb[0])};
            Z = nr3[0] * P[0] + nr3[1] * P[1] + nr3[2] * P[2];
        }
        const R th = static_cast<R>(theta);
        const R rel = term_rel(c2eps, Z / nr, th * th * rla * rlb, static_cast<R>(cl)) *
                      (1 + 64 * K_.eps);
        errs += static_cast<Quad>(term_err(th, rel) * (1 + 4 * K_.eps));
        if (eq3) {
            const Quad la = lengths[i], lb = lengths[j];
            const Quad sin_t = cl / (la * lb);
            Quad u[3];
            for (int k = 0; k < 3; ++k) u[k] = v[i][k] / la + v[j][k] / lb;
            const Quad lu = q_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            if (lu > 0) {
                for (int k = 0; k < 3; ++k) u[k] /= lu;
                const Quad w[3] = {c[1] * u[2] - c[2] * u[1], c[2] * u[0] - c[0] * u[2],
                                   c[0] * u[1] - c[1] * u[0]};
                auto dt = [](const Quad* x, const Quad* y) {
                    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
                };
                const Quad xy = sin_t * (dt(w, e1) * dt(u, e2) + dt(u, e1) * dt(w, e2)) / cl;
                S -= xy;
                mag += q_abs(xy);
            } else {
                errs += sin_t;
            }
            errs += static_cast<Quad>(term_err(th, rel) * (1 + 4 * K_.eps)) +
                    EQ3_FACTOR_ULPS * QUAD_EPS * 2 * q_sin(theta / 2);
        }
    }
    const Quad two_pi = static_cast<Quad>(6.283185307179586476925286766559L);
    *value = static_cast<R>(q_abs(S) / two_pi);
    // the quad sums' own rounding, and the value's to long double (the vertices'
    // errors are charged edge by edge, apart)
    *bound = static_cast<R>(sum_rounding(static_cast<Quad>(K_.c1) * QUAD_EPS, mag, errs) / two_pi) +
             K_.eps * *value;
}

// the solid angle of one convex piece, over pi (the unit of the cosine-weighted values,
// so that the vertices' and the band's charges, areas on the unit sphere over pi, carry
// over): Van Oosterom and Strackee's triangle formula over the fan from its first
// vertex, as exactff.kernel.solid_angle_sums (the Python engine's measure):
// tan(Omega / 2) = N / D with N = a . (b x c) in offset form, a0 . (e_b x e_c) (the
// offsets of Core::integrate, accurate for pieces small next to their distance), and
// D = |a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|; each triangle's rounding from C1
// roundoffs of the magnitudes of N's products and of 4 |a||b||c| through the atan2,
// the sum's from C1 roundoffs of its terms (sector.h's sum_rounding). A convex piece
// within one side of a plane through p: its triangles' angles share one sign.
void Core::integrate_solid(const Piece& q, int64_t f, R* value, R* bound) const {
    const R pi = 3.14159265358979323846264338327950288L;
    const size_t m = q.size();
    R S = 0, mag = 0, errs = 0;
    if (m < 3) {
        *value = 0;
        *bound = 0;
        return;
    }
    const V3 a = q[0].v;
    const R la = q[0].length;
    R unused;
    V3 eb = between(q[0], q[1], f, &unused);
    for (size_t i = 1; i + 1 < m; ++i) {
        const Vertex& B = q[i];
        const Vertex& C = q[i + 1];
        const V3 ec = between(q[0], C, f, &unused);
        const R p0 = eb.y * ec.z, p1 = eb.z * ec.y, p2 = eb.z * ec.x, p3 = eb.x * ec.z,
                p4 = eb.x * ec.y, p5 = eb.y * ec.x;
        const R N = a.x * (p0 - p1) + a.y * (p2 - p3) + a.z * (p4 - p5);
        const R TN = std::fabs(a.x) * (std::fabs(p0) + std::fabs(p1)) +
                     std::fabs(a.y) * (std::fabs(p2) + std::fabs(p3)) +
                     std::fabs(a.z) * (std::fabs(p4) + std::fabs(p5));
        const R lb = B.length, lc = C.length;
        const R D = la * lb * lc + dot(a, B.v) * lc + dot(a, C.v) * lb + dot(B.v, C.v) * la;
        const R TD = 4 * la * lb * lc;
        const R theta = std::atan2(N, D);
        const R eN = K_.c1 * K_.eps * TN, eD = K_.c1 * K_.eps * TD;
        const R r2 = N * N + D * D;
        // a perturbation too large for the first order: the angle's whole range
        const R dtheta = r2 > 0 ? std::min((std::fabs(D) * eN + std::fabs(N) * eD) / r2, pi) : 0;
        S += 2 * theta;
        mag += std::fabs(2 * theta);
        errs += 2 * dtheta + 4 * K_.eps * std::fabs(theta);
        eb = ec;
    }
    *value = std::fabs(S) / pi;
    // the sum of m - 2 terms: within m - 3 roundoffs of their magnitudes
    *bound = sum_rounding(std::max(K_.c1, static_cast<R>(m)) * K_.eps, mag, errs) / pi +
             K_.eps * *value;
}

}  // namespace exactff
