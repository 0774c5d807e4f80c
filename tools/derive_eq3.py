"""Derivation of the paper's Eq. 3 (corrected) from Eq. 2, checked with sympy.

Rosell & Vivo (WSCG 2000) print Eq. 3 with eta^2 where eta^-2 belongs. This script
states Eq. 2 (the image on the base disk of the great circle A x + B y + C z = 0 on the
upper hemisphere), proves that it is that image, states the corrected antiderivative
(Eq. 3) and proves ``d Area / dx = y(x)`` on both branches ``s = +-1``; it also shows
that the printed form fails the same check.

Run: ``python tools/derive_eq3.py`` (exit status 0 when every identity holds).
"""

import sys

import sympy as sp

A, B, C = sp.symbols("A B C", real=True)
eta, kappa = sp.symbols("eta kappa", positive=True)  # sqrt(B^2+C^2), sqrt(A^2+B^2+C^2)
t = sp.symbols("t", real=True)
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
    print("all identities hold" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
