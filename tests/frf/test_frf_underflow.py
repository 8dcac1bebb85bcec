"""Frequency responses whose |H| falls below float64's range (new-user findings F1 and F4).

F1: a geometric ``[chain]`` (30 masses, m0·10^i, k0·0.01^i, walls at both ends): far above the band
the transfer 0 → 29 is ~1e-300 … 1e-400; the phase printed where |H| underflowed to 0 was 180° off
at about half those points. F4: a ``[masses]`` scene of contrasts 1e-80 … 1e80 printed subnormals
(digits lost) and zeros without a note.

The references are written here from the scene's own numbers (the chain's i-th mass and springs, the
four masses and springs), assembled as K − ω²M + iωC in mpmath and solved by ``mpmath.lu_solve`` at
200 digits (the entries span ~60 decades; 300 digits agree to 1e-30).
"""

from __future__ import annotations

import json

import mpmath
import numpy as np
import pytest

import springchain as sc
from springchain.cli import main

TINY = float(np.finfo(float).tiny)
NOTE = "|H| is below the float64 range"
DPS = 200

N = 30
CHAIN = """name = "geochain"
[parameters]
m0 = 1e-20
q = 10.0
k0 = 1e30
r = 0.01
[chain]
n = 30
mass = "m0*q**i"
k = "k0*r**i"
left = "wall"
right = "wall"
"""
# dashpots beside every spring, c_i = tau k_i: H is complex (not only 0° / 180°)
CHAIN_DAMPED = CHAIN + """[[dampers]]
between = ["i", "i+1"]
c = "1e-4*k0*r**i"
"""

CONTRAST = """name = "contrast"
[parameters]
k1 = 1e80
k2 = 1e-80
k3 = 1.0
k4 = 1e40
ma = 1e-40
mb = 1.0
mc = 1e30
md = 1e-20
[masses]
a = "ma"
b = "mb"
c = "mc"
d = "md"
[[springs]]
between = ["wall", "a"]
k = "k1"
[[springs]]
between = ["a", "b"]
k = "k2"
[[springs]]
between = ["b", "c"]
k = "k3"
[[springs]]
between = ["c", "d"]
k = "k4"
"""


def _assemble(masses, springs, dampers=()):
    """M, K, C as mpmath matrices; springs and dampers ``(a, b, value)`` with -1 for a wall."""
    n = len(masses)
    M, K, C = mpmath.zeros(n, n), mpmath.zeros(n, n), mpmath.zeros(n, n)
    for i, m in enumerate(masses):
        M[i, i] = m
    for A, elements in ((K, springs), (C, dampers)):
        for a, b, v in elements:
            for p, sp in ((a, 1), (b, -1)):
                for q, sq in ((a, 1), (b, -1)):
                    if p >= 0 and q >= 0:
                        A[p, q] += sp * sq * v
    return M, K, C


def _chain_matrices(damped: bool):
    """Spring i joins masses i and i+1 (k0 r^i), the left wall spring is i = -1, the right one i = n-1."""
    with mpmath.workdps(DPS):
        m0, q, k0, r = mpmath.mpf("1e-20"), mpmath.mpf(10), mpmath.mpf("1e30"), mpmath.mpf("0.01")
        masses = [m0 * q**i for i in range(N)]
        springs = [(-1, 0, k0 / r)] + [(i, i + 1, k0 * r**i) for i in range(N - 1)] + [(N - 1, -1, k0 * r**(N - 1))]
        dampers = [(i, i + 1, mpmath.mpf("1e-4") * k0 * r**i) for i in range(N - 1)] if damped else []
        return _assemble(masses, springs, dampers)


def _contrast_matrices():
    with mpmath.workdps(DPS):
        f = mpmath.mpf
        masses = [f("1e-40"), f(1), f("1e30"), f("1e-20")]
        springs = [(-1, 0, f("1e80")), (0, 1, f("1e-80")), (1, 2, f(1)), (2, 3, f("1e40"))]
        return _assemble(masses, springs)


def _h(mats, w: float, i: int, o: int):
    """H = X_o / F_i at ω (mpmath complex, exact ω)."""
    M, K, C = mats
    with mpmath.workdps(DPS):
        W = mpmath.mpf(w)
        Z = K - W * W * M + mpmath.mpc(0, 1) * W * C
        F = mpmath.zeros(M.rows, 1)
        F[i] = 1
        return mpmath.lu_solve(Z, F)[o]


def _check(omega, magnitude, phase_deg, mats, i, o, picks):
    """Phase within 1e-9 rad where the exact |H| is below TINY (printed 0), |H| within 1e-10 elsewhere."""
    under = inside = 0
    for j in picks:
        h = _h(mats, float(omega[j]), i, o)
        exact_arg = float(mpmath.arg(h))
        if abs(h) < TINY:
            under += 1
            assert magnitude[j] == 0.0, (omega[j], magnitude[j], h)
            d = np.angle(np.exp(1j * (np.radians(phase_deg[j]) - exact_arg)))
            assert abs(d) <= 1e-9, (omega[j], phase_deg[j], mpmath.nstr(h, 8))
        else:
            inside += 1
            assert abs(magnitude[j] - float(abs(h))) <= 1e-10 * float(abs(h)), (omega[j], magnitude[j], h)
            d = np.angle(np.exp(1j * (np.radians(phase_deg[j]) - exact_arg)))
            assert abs(d) <= 1e-9
    return under, inside


def _picks(magnitude, count_under=14, count_inside=6):
    """Indices spread over the printed zeros and over the rest."""
    zero = np.flatnonzero(magnitude == 0)
    rest = np.flatnonzero(magnitude > 0)
    take = lambda a, c: a[np.unique(np.linspace(0, a.size - 1, c).round().astype(int))] if a.size else a  # noqa: E731
    return np.concatenate([take(zero, count_under), take(rest, count_inside)])


@pytest.mark.parametrize("damped", [False, True])
def test_chain_phase_where_magnitude_underflows(tmp_path, damped):
    """F1: the [chain] route (dynamic-stiffness sweep, 30 > 24 masses) keeps arg H where |H| < 1e-308."""
    path = tmp_path / "geochain.toml"
    path.write_text(CHAIN_DAMPED if damped else CHAIN)
    r = sc.frf(path, 0, N - 1, omega_min=10.0, omega_max=1e6, points=80)
    mag, ph = r.magnitude, r.phase
    assert np.count_nonzero(mag == 0) >= 20  # the case is what it claims: many frequencies below the range
    assert np.all((mag == 0) | (mag >= TINY))  # no subnormal printed
    assert sum(n.startswith(NOTE) for n in r.notes) == 1
    under, inside = _check(r.omega, mag, ph, _chain_matrices(damped), 0, N - 1, _picks(mag))
    assert under >= 10 and inside >= 3


def test_chain_kernels_carry_the_exponent():
    """Both compiled sweeps and the mpmath sweep give the mantissa and exponent of H (no Python loop
    over masses): |H| ~ 1e-360 recovered to 1e-12, arg H to 1e-9 rad."""
    from springchain.numeric.frf.chain import chain_elements, chain_receptance, mp_chain_receptance
    from springchain.numeric.modes.elements import Elements
    from springchain._modules import system_of
    from springchain._scenes import load
    import tempfile, pathlib

    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d) / "geochain.toml"
        p.write_text(CHAIN_DAMPED)
        system, _ = system_of(load(p))
    el = Elements.from_system(system)
    ch = chain_elements(el.masses, el.spring_ends, el.stiffness, el.damper_ends, el.damping)
    omega = np.array([6615.244315890085, 31399.745827893523, 2.0e5])
    mats = _chain_matrices(True)
    refs = [_h(mats, w, 0, N - 1) for w in omega]
    assert all(abs(h) < mpmath.mpf("1e-320") for h in refs)
    for certify in (False, True):
        m, e = chain_receptance(ch, omega, 0, N - 1, certify=certify, scaled=True)
        assert np.all(np.abs(m) > 0.4)
        for j, h in enumerate(refs):
            got = mpmath.mpc(m[j]) * mpmath.mpf(2) ** int(e[j])
            assert abs(got - h) <= 1e-12 * abs(h), (certify, omega[j])
        assert np.all(chain_receptance(ch, omega, 0, N - 1, certify=certify) == 0)  # unscaled: below range
    m, e = mp_chain_receptance(ch, float(omega[0]), 0, N - 1, scaled=True)
    assert abs(mpmath.mpc(m) * mpmath.mpf(2) ** e - refs[0]) <= 1e-14 * abs(refs[0])


def test_masses_underflow_noted_and_phase_kept(tmp_path, capsys):
    """F4: the [masses] route notes |H| below 2.2e-308, prints 0 there (no subnormal), keeps the phase,
    and leaves the magnitudes in range as they were (1e-10 of the 200-digit solve)."""
    path = tmp_path / "contrast.toml"
    path.write_text(CONTRAST)
    assert main(["frf", str(path), "--input", "d", "--output", "a", "--json"]) in (0, None)
    out = json.loads(capsys.readouterr().out)
    mag, ph = np.array(out["magnitude"]), np.array(out["phase"])
    assert np.count_nonzero(mag == 0) >= 50
    assert np.all((mag == 0) | (mag >= TINY))
    assert sum(n.startswith(NOTE) for n in out["notes"]) == 1
    under, inside = _check(np.array(out["omega"]), mag, ph, _contrast_matrices(), 3, 0,
                           _picks(mag, count_under=60, count_inside=60))
    assert under >= 40 and inside >= 40


def test_no_note_when_in_range(tmp_path):
    """A response that stays in range gets no underflow note (the note is not said by default)."""
    path = tmp_path / "geochain.toml"
    path.write_text(CHAIN)
    r = sc.frf(path, 0, 1, omega_min=1e20, omega_max=1e24, points=20)
    assert np.all(r.magnitude > TINY)
    assert not any(n.startswith(NOTE) for n in r.notes)
