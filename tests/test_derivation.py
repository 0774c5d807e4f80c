"""The sympy derivation of Eq. 3 (tools/derive_eq3.py) holds, and matches the kernel."""

import importlib.util
import math
import os

import pytest

from exactff.kernel import eq3_edge_integral

TOOL = os.path.join(os.path.dirname(__file__), "..", "tools", "derive_eq3.py")


def load_tool():
    spec = importlib.util.spec_from_file_location("derive_eq3", TOOL)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_eq3_derivative_is_eq2_and_printed_form_is_not(capsys):
    assert load_tool().main() == 0
    assert "all identities hold" in capsys.readouterr().out


def test_kernel_edge_integral_vs_sympy_antiderivative():
    # a span on the + branch between two x values: the kernel against Area(x1) - Area(x0)
    # from the sympy expression (independent evaluation at 30 digits)
    tool = load_tool()
    sp = tool.sp
    a, b = [0.2, 0.9, 0.5], [0.7, 0.4, 0.6]
    m = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    k = math.sqrt(sum(c * c for c in m))
    Av, Bv, Cv = (c / k for c in m)
    eta_v = math.hypot(Bv, Cv)
    subs = {tool.A: Av, tool.B: Bv, tool.C: Cv, tool.eta: eta_v, tool.kappa: 1}

    def branch(p):
        # s C sqrt(eta^2 - x^2) = eta^2 y + A B x on branch s
        n = math.sqrt(sum(c * c for c in p))
        return math.copysign(1.0, Cv * (eta_v**2 * p[1] / n + Av * Bv * p[0] / n))

    def area_at(p, s):
        n = math.sqrt(sum(c * c for c in p))
        tv = math.asin(p[0] / n / eta_v)
        return tool.eq3(s).subs(subs).subs(tool.t, tv)

    # both end points on one branch: the arc (shorter than pi) passes no x-extreme
    s = branch(a)
    assert branch(b) == s
    ref = sp.N(area_at(b, s) - area_at(a, s), 30)
    assert eq3_edge_integral(a, b) == pytest.approx(float(ref), abs=1e-15)
