"""The compiled closed form of the unoccluded area pair (exactff/_core/closed_form.cpp,
dilog.h; issue 49): its dilogarithm against mpmath, and a row's compiled sums against
the edge-pair integrals one by one and against mpmath.

The closed form's values and estimates as a whole are held to mpmath and Howell's
catalogue in tests/test_closed_form.py and tests/test_area.py.
"""

import mpmath as mp
import numpy as np
import pytest

from exactff import _tolerances as tol
from exactff.area import _closed
from exactff.area.edge_integrals import edge_log_integrals, edge_pair_sums, mp_edge_log_integral

#: The unit roundoff of doubles, the dilogarithm's error unit here.
U = 2.0 ** -53


def _li2_reference(z):
    """mpmath's Li2 at 40 digits, and as many more as the imaginary part is below 1 (at
    40 digits alone mpmath returns 0 for an imaginary part of 1e-58 next to a real part
    of 0.7)."""
    digits = 40 + (int(-np.log10(abs(z.imag))) if z.imag != 0 else 0)
    with mp.workdps(digits):
        return mp.polylog(2, mp.mpc(z.real, z.imag))


def _errors(Z):
    """Per point: the absolute error in units of U of max(1, |Li2|), and the imaginary
    part's relative error in units of U (0 where the reference's is 0)."""
    got = _closed.li2(Z)
    out = []
    with mp.workdps(80):
        for z, g in zip(Z, got):
            r = _li2_reference(z)
            err = abs(mp.mpc(g.real, g.imag) - r) / max(1, abs(r)) / U
            im = abs(g.imag - r.imag) / abs(r.imag) / U if r.imag != 0 else 0
            out.append((float(err), float(im)))
    return np.array(out)


def test_dilogarithm_against_mpmath_over_the_plane():
    # inside the unit disk, on the circle (where the closed form takes Im Li2(-e^{2 i phi}),
    # Clausen's function) and outside it: within 8 units of max(1, |Li2|) (measured at
    # most 4.7)
    rng = np.random.default_rng(49)
    r, th = np.sqrt(rng.random(600)), rng.uniform(-np.pi, np.pi, 600)
    disk = r * np.exp(1j * th)
    circle = np.exp(1j * rng.uniform(-np.pi, np.pi, 300))
    outside = rng.uniform(1, 4, 200) * np.exp(1j * rng.uniform(-3.1, 3.1, 200))
    special = np.array([0, 1, -1, 1j, -1j, 0.5, 0.5 + 0.5j, 0.5 - 0.5j, -0.5, 1e-300 + 1e-300j,
                        1e-20j, 1 + 1e-17j, 1 - 1e-10j, np.exp(1e-8j), -1 + 1e-12j, 2j])
    for Z in (disk, circle, outside, special):
        err = _errors(Z)
        assert np.all(np.isfinite(_closed.li2(Z)))
        assert err[:, 0].max() <= 8.0, Z[np.argmax(err[:, 0])]


def test_dilogarithm_near_the_real_axis_left_of_a_half_vs_mpmath():
    # where scipy's complex spence was wrong (x = -(2 - sqrt 3), an imaginary part of 0.028
    # for 7.5e-17), and the whole band Re z <= 1/2, |Im z| from 1e-300 to 1e-6: the
    # imaginary part, the one the closed form takes, within 8 units of itself (measured at
    # most 1.9), the whole value within 8 units of max(1, |Li2|)
    rng = np.random.default_rng(50)
    a = -0.2679491924311228
    band = np.concatenate([
        [a + 8.41410012693027e-17j, a - 8.41410012693027e-17j, a + 1e-14j, a - 1e-300j,
         -0.99 + 1e-12j, 0.3 - 1e-16j, 0.5 + 1e-9j, -1 + 1e-200j, -1e-10 + 1e-20j],
        rng.uniform(-1, 0.5, 100)
        + 1j * rng.choice([-1, 1], 100) * 10 ** rng.uniform(-300, -6, 100)])
    err = _errors(band)
    assert err[:, 0].max() <= 8.0, band[np.argmax(err[:, 0])]
    assert err[:, 1].max() <= 8.0, band[np.argmax(err[:, 1])]


def test_dilogarithm_of_small_arguments_is_relatively_accurate():
    # Li2(z) ~ z near 0 (the closed form's Li2(-rho e^{2 i phi}) of far edges, rho small):
    # within 8 units of itself (measured at most 1), both parts where they are not
    # below 1e-3 of |z|
    rng = np.random.default_rng(53)
    Z = 10 ** rng.uniform(-300, -2, 300) * np.exp(1j * rng.uniform(-np.pi, np.pi, 300))
    got = _closed.li2(Z)
    with mp.workdps(60):
        for z, g in zip(Z, got):
            r = _li2_reference(z)
            assert abs(mp.mpc(g.real, g.imag) - r) <= 8 * U * abs(r), (z, g, r)
            for part, ref in ((g.real, r.real), (g.imag, r.imag)):
                if abs(ref) > 1e-3 * abs(r):
                    assert abs(part - ref) <= 8 * U * abs(ref), (z, g, r)


def _edge_cases(rng, n):
    """Random edge pairs of every kind: skew, sharing a vertex, crossing, parallel,
    collinear, 1e-8 from parallel."""
    out = []
    for k in range(n):
        a, e, b, f = (rng.normal(size=3) for _ in range(4))
        kind = k % 6
        if kind == 1:
            b = a + e
        elif kind == 2:
            f = (a + 0.5 * e) - b + rng.normal() * 1e-3 * e
        elif kind == 3:
            f = -0.7 * e
        elif kind == 4:
            b, f = a + 2.5 * e, 1.3 * e
        elif kind == 5:
            f = 0.8 * e + 1e-8 * rng.normal(size=3)
        out.append((a, e, b, f))
    return [np.array(x) for x in zip(*out)]


def test_edge_integrals_against_mpmath():
    # each edge pair's J within its estimate, AREA_CLOSED_ULPS units of EPS of its terms'
    # magnitudes, of mpmath's at 30 digits more than its own terms' magnitudes (edges
    # parallel in floats are not quite in mpmath: its skew form's terms reach 1e19)
    a, e, b, f = _edge_cases(np.random.default_rng(51), 60)
    J, M = edge_log_integrals(a, e, b, f)
    for k in range(len(J)):
        args = [[mp.mpf(float(v)) for v in x[k]] for x in (a, e, b, f)]
        with mp.workdps(30):
            _, mag = mp_edge_log_integral(*args)
        with mp.workdps(30 + int(mp.log10(max(1, mag)))):
            ref, _ = mp_edge_log_integral(*args)
        assert abs(J[k] - float(ref)) <= tol.AREA_CLOSED_ULPS * tol.EPS * M[k], (k, J[k], ref)


def test_row_sums_are_the_edge_integrals_summed():
    # the row's compiled sums (edge_pair_sums) are the edge-pair integrals of the scaled
    # edges, bit for bit, summed with their rounding; e . f = 0 pairs left out
    rng = np.random.default_rng(52)
    P = np.array([[0, 0, 0], [1, 0, 0], [1.2, 0.9, 0], [0.1, 1, 0]], float)
    Qs = [np.array([[0, 0, 1], [0, 1, 1.5], [1, 1, 1], [1, 0, 1.2]], float) + rng.normal(size=3),
          np.array([[0, 0, 0], [0, 1, 0], [0, 1, 1]], float),     # perpendicular edges
          np.array([[3, 0, 2], [2, 0, 2], [2.5, 1, 2]], float)]
    VQ = np.concatenate(Qs)
    qo = np.array([0, 4, 7, 10])
    inv = np.array([0.5, 1.0, 0.25])
    scale = np.array([1.5, 2.5, 3.5])
    VP = np.concatenate([P] * 3)
    po = np.array([0, 4, 8, 12])
    v, ev, owner, ip, iq, ef, J, c = edge_pair_sums(VP, po, VQ, qo, inv, scale)

    def nxt(i, o):
        # vertex i's successor in its ring of offsets o
        r = np.searchsorted(o, i, side="right")
        return i + 1 if i + 1 < o[r] else o[r - 1]

    expect_v, expect_e, rows = np.zeros(3), np.zeros(3), []
    for p in range(3):
        for i in range(po[p], po[p + 1]):
            for j in range(qo[p], qo[p + 1]):
                e = (VP[nxt(i, po)] - VP[i]) * inv[p]
                f = (VQ[nxt(j, qo)] - VQ[j]) * inv[p]
                d = float(e @ f)
                if d == 0:
                    continue
                Jk, Mk = edge_log_integrals(((VP[i] - VQ[j]) * inv[p])[None], e[None],
                                            np.zeros((1, 3)), f[None])
                ck = tol.AREA_CLOSED_ULPS * tol.EPS * abs(d) * Mk[0] / scale[p]
                rows.append((p, i, j, Jk[0], ck))
                expect_v[p] += d * Jk[0] / scale[p]
                expect_e[p] += ck
    assert owner.tolist() == [r[0] for r in rows]
    assert ip.tolist() == [r[1] for r in rows] and iq.tolist() == [r[2] for r in rows]
    assert J.tolist() == [r[3] for r in rows] and c.tolist() == [r[4] for r in rows]
    assert np.allclose(v, expect_v, rtol=1e-14, atol=0) and np.allclose(ev, expect_e, rtol=1e-14)
    assert 0 < len(J) < 4 * 4 + 4 * 3 + 4 * 3          # some perpendicular pairs left out


def test_compiled_arguments_are_checked():
    with pytest.raises(ValueError, match="row_pairs"):
        _closed.row_pairs(np.zeros((4, 3)), np.array([0, 4]), np.zeros((3, 3)), np.array([0, 3]),
                          np.ones(2), np.ones(2), 0.0, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(IndexError, match="row_pairs"):
        _closed.row_pairs(np.zeros((4, 3)), np.array([0, 5]), np.zeros((3, 3)), np.array([0, 3]),
                          np.ones(1), np.ones(1), 0.0, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="edge_log_integrals"):
        _closed.edge_log_integrals(np.zeros((2, 3)), np.zeros((1, 3)), np.zeros((2, 3)),
                                   np.zeros((2, 3)), 0.0, 0.0, 0.0, 0.0, 0.0)
