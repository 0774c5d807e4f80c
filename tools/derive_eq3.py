"""Derivation of the paper's Eq. 3 (corrected) from Eq. 2, checked with sympy.

Rosell & Vivo (WSCG 2000) print Eq. 3 with eta^2 where eta^-2 belongs. This script
states Eq. 2 (the image on the base disk of the great circle A x + B y + C z = 0 on the
upper hemisphere), proves that it is that image, states the corrected antiderivative
(Eq. 3) and proves ``d Area / dx = y(x)`` on both branches ``s = +-1``; it also shows
that the printed form fails the same check.

It then derives the stable form the integrators evaluate (issue 51). With kappa = 1
(unit plane normal m = (A, B, C)) the great circle is ``u(t) = cos t w + sin t w_perp``
with ``w`` at its x-maximum and ``w_perp = m x w``: ``x = eta cos t`` and ``y = (-A B cos t +
C sin t) / eta``. That point lies on the branch ``s = sign(sin t)`` of Eq. 2 (so ``s sigma
= 1`` on every monotone span), and on a span Eq. 3 at ``x(t)`` equals

    G(t) = (1/2) [ -C t + C sin t cos t - A B cos^2 t ]

up to a constant of the span (``asin(cos t) = -sigma t + const``). Summed over the spans
of an arc the constants drop (that is what the span splitting does) and

    G(t1) - G(t0) = (1/2) [ -C (t1 - t0) + sin(t1 - t0) (C cos(t0 + t1) + A B sin(t0 + t1)) ]

in which every term is O(t1 - t0): the large ``C asin`` terms are subtracted
analytically. The factor ``C cos(t0 + t1) + A B sin(t0 + t1)`` is ``d(x y)/dt`` at the
arc's midpoint ``t_m = (t0 + t1) / 2``, i.e. ``v_x u_y + u_x v_y`` with ``u = u(t_m)`` and
``v = m x u`` its tangent: no eta, no rotation of the frame, only the arc's midpoint.

Run: ``python tools/derive_eq3.py`` (exit status 0 when every identity holds).
"""

import sys

import sympy as sp

A, B, C = sp.symbols("A B C", real=True)
eta, kappa = sp.symbols("eta kappa", positive=True)  # sqrt(B^2+C^2), sqrt(A^2+B^2+C^2)
t, phi = sp.symbols("t phi", real=True)
# x runs over (-eta/kappa, eta/kappa); with x = (eta/kappa) sin t, t in (-pi/2, pi/2),
# sqrt(eta^2 - kappa^2 x^2) = eta cos t and asin(kappa x / eta) = t exactly
x = eta * sp.sin(t) / kappa
root = eta * sp.cos(t)
asin_kx_eta = t


def eq2(s):
    """Eq. 2: y(x) on branch s."""
    return (-A * B * x + s * C * root) / eta**2


def eq3(s):
    """Eq. 3, corrected: the antiderivative of Eq. 2 on branch s."""
    return (s * C * asin_kx_eta
            + s * (kappa * C * x / eta**2) * root
            - (kappa * A * B / eta**2) * x**2) / (2 * kappa)


def eq3_as_printed(s):
    """Eq. 3 as printed: eta^2 in the numerators of Psi and Omega."""
    return (s * C * asin_kx_eta
            + s * (kappa * C * x * eta**2) * root
            - (kappa * A * B * eta**2) * x**2) / (2 * kappa)


def stable_parametrisation():
    """The great circle of unit normal m = (A, B, C) with eta = sqrt(B^2 + C^2) > 0, written
    B = eta cos(phi), C = eta sin(phi), A^2 = 1 - eta^2: w (x-maximum), w_perp = m x w, as
    explicit vectors."""
    m = sp.Matrix([A, eta * sp.cos(phi), eta * sp.sin(phi)])
    w = (sp.Matrix([1, 0, 0]) - A * m) / eta
    w_perp = m.cross(w)
    return m, w, w_perp


def on_sphere(expr):
    """``expr`` reduced modulo A^2 + eta^2 - 1 (m a unit vector), simplified: 0 for an
    identity that holds for every unit normal."""
    expr = sp.expand(sp.expand_trig(sp.expand(expr)))
    num, den = sp.fraction(sp.together(expr))
    num = sp.rem(sp.expand(num), A**2 + eta**2 - 1, A)
    return sp.simplify(sp.expand_trig(sp.expand(num)))


def stable_form_residuals():
    """The identities behind the stable form; each residual simplifies to 0."""
    m, w, w_perp = stable_parametrisation()
    e, Av, B_, C_ = eta, A, eta * sp.cos(phi), eta * sp.sin(phi)
    out = {}
    u = sp.cos(t) * w + sp.sin(t) * w_perp
    # the basis: unit, orthogonal, in the plane; x = eta cos t; y as stated
    out["w, w_perp orthonormal in the plane"] = [
        on_sphere(w.dot(w) - 1), on_sphere(w_perp.dot(w_perp) - 1),
        on_sphere(w.dot(w_perp)), on_sphere(m.dot(w)), on_sphere(m.dot(w_perp))]
    out["x(t) = eta cos t"] = [on_sphere(u[0] - e * sp.cos(t))]
    y_t = (-Av * B_ * sp.cos(t) + C_ * sp.sin(t)) / e
    out["y(t) = (-A B cos t + C sin t) / eta"] = [on_sphere(u[1] - y_t)]
    # branch: with sigma = sign(sin t), sqrt(eta^2 - x^2) = eta sigma sin t, and Eq. 2 on
    # branch s = sigma gives y(t) (sigma^2 = 1)
    sig = sp.symbols("sigma", real=True)
    eq2_sigma = (-Av * B_ * e * sp.cos(t) + sig * C_ * (e * sig * sp.sin(t))) / e**2
    out["Eq. 2 on branch s = sign(sin t) is y(t)"] = [
        on_sphere((eq2_sigma - y_t).subs(sig**2, 1))]
    # Eq. 3 (corrected, kappa = 1) at x(t) on branch sigma, with asin(cos t) = c - sigma t
    # on the span (d/dt asin(cos t) = -sin t / |sin t| = -sigma): its t-derivative is G'
    c_span = sp.symbols("c_span", real=True)
    x_t = e * sp.cos(t)
    eq3_t = (sig * C_ * (c_span - sig * t) + sig * (C_ * x_t / e**2) * (e * sig * sp.sin(t))
             - (Av * B_ / e**2) * x_t**2) / 2
    G = (-C_ * t + C_ * sp.sin(t) * sp.cos(t) - Av * B_ * sp.cos(t) ** 2) / 2
    out["d/dt Eq. 3(x(t)) on branch sigma = G'(t)"] = [
        on_sphere(sp.expand(sp.diff(eq3_t, t) - sp.diff(G, t)).subs(sig**2, 1))]
    # and G is the integral of y dx along u(t)
    out["G'(t) = y(t) x'(t)"] = [on_sphere(sp.diff(G, t) - y_t * sp.diff(x_t, t))]
    # the difference over [t0, t1]: every term O(t1 - t0)
    t0, t1 = sp.symbols("t0 t1", real=True)
    stable = (-C_ * (t1 - t0) + sp.sin(t1 - t0) * (C_ * sp.cos(t0 + t1)
                                                  + Av * B_ * sp.sin(t0 + t1))) / 2
    out["G(t1) - G(t0) = stable form"] = [
        on_sphere(sp.expand_trig(sp.expand(G.subs(t, t1) - G.subs(t, t0) - stable)))]
    # its factor is d(x y)/dt at the midpoint: v_x u_y + u_x v_y with v = m x u
    tm = (t0 + t1) / 2
    um = sp.cos(tm) * w + sp.sin(tm) * w_perp
    vm = m.cross(um)
    out["m x u = du/dt"] = [on_sphere(e_) for e_ in (vm - sp.diff(u, t).subs(t, tm))]
    factor = C_ * sp.cos(t0 + t1) + Av * B_ * sp.sin(t0 + t1)
    out["C cos(t0+t1) + A B sin(t0+t1) = v_x u_y + u_x v_y at the midpoint"] = [
        on_sphere(sp.expand_trig(sp.expand(vm[0] * um[1] + um[0] * vm[1] - factor)))]
    # and x y at the ends: the factor times sin(t1 - t0) is x1 y1 - x0 y0 (which
    # telescopes around a closed contour)
    xy = lambda tv: (e * sp.cos(tv)) * y_t.subs(t, tv)
    out["sin(t1 - t0) factor = x1 y1 - x0 y0"] = [
        on_sphere(sp.expand_trig(sp.expand(sp.sin(t1 - t0) * factor - (xy(t1) - xy(t0)))))]
    return out


def derivative_residual(area, s):
    """d Area / dx - y(x), with d/dx = (d/dt) / (dx/dt)."""
    return sp.simplify(sp.diff(area(s), t) / sp.diff(x, t) - eq2(s))


def great_circle_residual(s):
    """(A x + B y)^2 - C^2 z^2 with z^2 = 1 - x^2 - y^2: zero when (x, y) is the image of
    a point of the plane A x + B y + C z = 0 on the unit sphere."""
    y = eq2(s)
    expr = (A * x + B * y) ** 2 - C**2 * (1 - x**2 - y**2)
    expr = expr.subs({eta: sp.sqrt(B**2 + C**2), kappa: sp.sqrt(A**2 + B**2 + C**2)})
    return sp.simplify(sp.expand(expr))


def main():
    ok = True
    for s in (1, -1):
        residual = derivative_residual(eq3, s)
        print(f"branch {s:+d}: d/dx Eq.3 - Eq.2 = {residual}")
        ok &= residual == 0
        circle = great_circle_residual(s)
        print(f"branch {s:+d}: (A x + B y)^2 - C^2 z^2 on the sphere = {circle}")
        ok &= circle == 0
    printed = derivative_residual(eq3_as_printed, 1)
    spot = sp.N(printed.subs({A: 0.3, B: 0.5, C: 0.6, eta: (0.5**2 + 0.6**2) ** 0.5,
                              kappa: (0.3**2 + 0.5**2 + 0.6**2) ** 0.5, t: 0.2}))
    print(f"printed Eq. 3 (eta^2 typo): d/dx - Eq.2 at a sample point = {spot}")
    ok &= abs(spot) > 1e-6
    for name, residuals in stable_form_residuals().items():
        print(f"stable form: {name}: {residuals}")
        ok &= all(r == 0 for r in residuals)
    print("all identities hold" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
