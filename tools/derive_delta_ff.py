"""Delta form factors of the cubic tetrahedron and the hemicube, derived with sympy.

For a differential receiver at the origin with unit normal n and a cell of area dA at
point x on a plane face with unit normal m (facing the origin):

    dF = cos(theta_p) cos(theta_c) dA / (pi r^2),  cos(theta_p) = n.x / r,
    cos(theta_c) = -m.x / r (m pointing away from the origin: +m.x / r), r = |x|.

Cubic tetrahedron (Beran-Koehn & Pavicic 1991): in cube coordinates n = (1, 1, 1)/sqrt 3,
face x' = 1, point (1, v, w), face normal (1, 0, 0):
    dF = (1 + v + w) dA / (sqrt(3) pi (1 + v^2 + w^2)^2).
Hemicube (Cohen & Greenberg 1985): n = z; top face z = 1: dA / (pi (x^2 + y^2 + 1)^2);
side face x = 1 at (1, y, z): z dA / (pi (1 + y^2 + z^2)^2).

Run: ``python tools/derive_delta_ff.py`` (exit status 0 when the formulas match).
"""

import sys

import sympy as sp


def delta_ff(x, n, m):
    r = sp.sqrt(sum(c * c for c in x))
    cos_p = sum(a * b for a, b in zip(n, x)) / r
    cos_c = sum(a * b for a, b in zip(m, x)) / r
    return sp.simplify(cos_p * cos_c / (sp.pi * r**2))


def main():
    v, w, x, y, z = sp.symbols("v w x y z", real=True)
    ok = True
    cases = [
        ("cubic tetrahedron, face x'=1", delta_ff((1, v, w), [1 / sp.sqrt(3)] * 3, (1, 0, 0)),
         (1 + v + w) / (sp.sqrt(3) * sp.pi * (1 + v**2 + w**2) ** 2)),
        ("hemicube top", delta_ff((x, y, 1), (0, 0, 1), (0, 0, 1)),
         1 / (sp.pi * (x**2 + y**2 + 1) ** 2)),
        ("hemicube side x=1", delta_ff((1, y, z), (0, 0, 1), (1, 0, 0)),
         z / (sp.pi * (1 + y**2 + z**2) ** 2)),
    ]
    for name, derived, used in cases:
        diff = sp.simplify(derived - used)
        print(f"{name}: derived - used = {diff}")
        ok &= diff == 0
    print("all delta form factors match" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
