// Shewchuk's expansion arithmetic on the input's doubles (J. R. Shewchuk, "Adaptive
// precision floating-point arithmetic and fast robust geometric predicates", 1997): sums
// and products of doubles held exactly as nonoverlapping sums of doubles. Two
// representations, for two uses:
//   - Expansion: on the stack, increasing magnitude, for the exact signs of the
//     visibility core's predicates (predicates.h);
//   - Exp: a std::vector, compressed after each product so that it stays a few terms
//     long, for the BSP build's exact crossings (bsp_build.cpp), with its value in
//     quadruple precision (e_value).

#ifndef EXACTFF_CORE_EXPANSION_H
#define EXACTFF_CORE_EXPANSION_H

#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "precision.h"

namespace exactff {

// ---- exact signs of float input (Shewchuk's expansion arithmetic), for the cases the
// band leaves open: a vertex of the input and a plane through p and two input points
// (or with a normal of the input), whose float sign is not sure. Expansions live on the
// stack (the longest here, a 3 x 3 determinant of differences, has at most 192 terms).
struct Expansion {
    std::array<double, 200> c;
    int n = 0;
};

inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    double bv = x - a;
    y = (a - (x - bv)) + (b - bv);
}

// e + b, nonoverlapping increasing (Shewchuk's grow-expansion, zeros dropped)
inline void grow(Expansion& e, double b) {
    double q = b;
    int k = 0;
    for (int i = 0; i < e.n; ++i) {
        double x, y;
        two_sum(q, e.c[i], x, y);
        if (y != 0) e.c[k++] = y;
        q = x;
    }
    if (q != 0 || k == 0) e.c[k++] = q;
    e.n = k;
    // a nonoverlapping expansion of these determinants holds a few hundred bits: a
    // length near the capacity would mean a defect, never silently overrun
    if (k >= static_cast<int>(e.c.size()) - 1) throw std::overflow_error("expansion too long");
}

inline Expansion add(const Expansion& e, const Expansion& f) {
    Expansion h = e;
    for (int i = 0; i < f.n; ++i) grow(h, f.c[i]);
    return h;
}

inline Expansion scale(const Expansion& e, double b) {
    Expansion h;
    for (int i = 0; i < e.n; ++i) {
        double x = e.c[i] * b;
        double y = std::fma(e.c[i], b, -x);
        grow(h, y);
        grow(h, x);
    }
    return h;
}

inline Expansion mul(const Expansion& e, const Expansion& f) {
    Expansion h;
    for (int i = 0; i < f.n; ++i) h = add(h, scale(e, f.c[i]));
    return h;
}

inline Expansion neg(Expansion e) {
    for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
    return e;
}

inline int sign(const Expansion& e) {
    for (int i = e.n - 1; i >= 0; --i)
        if (e.c[i] != 0) return e.c[i] > 0 ? 1 : -1;
    return 0;
}

inline Expansion diff(double a, double b) {  // a - b exactly
    Expansion e;
    double x, y;
    two_sum(a, -b, x, y);
    if (y != 0) e.c[e.n++] = y;
    e.c[e.n++] = x;
    return e;
}

// h += sign * e * f, in place (every product two-product split, grown into h)
inline void mul_into(Expansion& h, const Expansion& e, const Expansion& f, double sign) {
    for (int j = 0; j < f.n; ++j) {
        const double fj = sign * f.c[j];
        for (int i = 0; i < e.n; ++i) {
            const double x = e.c[i] * fj;
            grow(h, std::fma(e.c[i], fj, -x));
            grow(h, x);
        }
    }
}

// ---- exact arithmetic on the input's doubles (Shewchuk's expansions, nonoverlapping,
// increasing magnitude, zeros dropped; compressed after each product so that they stay
// a few terms long): the crossings the quadruple precision cannot place, where a chain
// of grazing splits would compound its rounding (Builder::exact_crossing)
using Exp = std::vector<double>;

// e + f (repeated grow-expansion)
inline Exp e_add(const Exp& e, const Exp& f) {
    Exp h = e;
    for (double b : f) {
        double q = b;
        size_t k = 0;
        for (size_t i = 0; i < h.size(); ++i) {
            double x, y;
            two_sum(q, h[i], x, y);
            if (y != 0) h[k++] = y;
            q = x;
        }
        h.resize(k);
        if (q != 0) h.push_back(q);
    }
    return h;
}

// Shewchuk's compress: the same value in the fewest nonoverlapping terms
inline void e_compress(Exp& e) {
    if (e.size() < 2) return;
    const size_t m = e.size();
    std::vector<double> g(m);
    size_t bottom = m - 1;
    double q = e[m - 1];
    for (size_t i = m - 1; i-- > 0;) {
        double x, y;
        two_sum(q, e[i], x, y);
        if (y != 0) {
            g[bottom--] = x;
            q = y;
        } else {
            q = x;
        }
    }
    g[bottom] = q;
    Exp h;
    for (size_t i = bottom + 1; i < m; ++i) {
        double x, y;
        two_sum(g[i], q, x, y);
        q = x;
        if (y != 0) h.push_back(y);
    }
    if (q != 0) h.push_back(q);
    e.swap(h);
}

inline Exp e_mul(const Exp& e, const Exp& f) {
    Exp h;
    for (double b : f) {
        Exp t;
        for (double a : e) {
            const double x = a * b;
            const double y = std::fma(a, b, -x);
            if (y != 0) t.push_back(y);
            if (x != 0) t.push_back(x);
        }
        // t's terms overlap one another: add them one at a time
        Exp acc;
        for (double v : t) acc = e_add(acc, Exp{v});
        h = e_add(h, acc);
    }
    e_compress(h);
    return h;
}

inline Exp e_sub(const Exp& e, Exp f) {
    for (double& v : f) v = -v;
    Exp h = e_add(e, f);
    e_compress(h);
    return h;
}

inline Exp e_of(double a) { return a != 0 ? Exp{a} : Exp{}; }

// its value in quadruple precision (the terms summed from the smallest: within a few
// roundoffs of it)
inline Quad e_value(const Exp& e) {
    Quad s = 0;
    for (double v : e) s += Quad(v);
    return s;
}

}  // namespace exactff

#endif
