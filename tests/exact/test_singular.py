"""Singular points of the one-mode closed forms (numeric.exact.special), against mpmath at 60 digits.

Tolerances. The inputs (ω, Ω or ζ, t) are floats that mpmath takes as exact,
so the only error measured is the kernel's own rounding. A kernel that is
backward stable in its inputs (each input perturbed by a few ulps) has
forward error at most ``c·ε·(|f| + Σ_j |x_j ∂f/∂x_j|)``: the function's own
componentwise condition number, computed here by mpmath. We require
``c = 16``; the kernels measure at most 6 on these grids (the sine response
of a rigid mode driven at Ω = 1e-300; 4.3 for the cosine response at
Ω = 1000ω; about 1 at and next to every singular point), while the textbook formulas miss by factors
of 1e4 and more at 1e-12 from resonance or critical damping (checked below,
so the tolerance can fail).
"""

from __future__ import annotations

import itertools
import warnings

import mpmath as mp
import numpy as np
import pytest

from springchain.numeric.exact.special import (FreeResponse, damped_free, damped_free_rate, omega_from_omega2, sinc, sinhc, tsinc,
                             undamped_forced_cos, undamped_forced_sin)

EPS = np.finfo(float).eps
C_TOL = 16.0
DPS = 60
#: Relative distances from each singular point (0: the point itself).
NEAR = [0.0, 1e-8, -1e-8, 1e-12, -1e-12, 1e-15, -1e-15]


def mpf(x) -> mp.mpf:
    return mp.mpf(float(x))


def condition(f, args) -> mp.mpf:
    """``|f| + Σ_j |x_j ∂f/∂x_j|`` at mpmath precision."""
    total = abs(f(*args))
    for j, xj in enumerate(args):
        if xj == 0:
            continue
        total += abs(xj * mp.diff(lambda u, j=j: f(*(args[:j] + (u,) + args[j + 1:])), xj))
    return total


def scaled_error(got: float, f, args) -> float:
    """Error of ``got`` in units of ``ε·condition``."""
    with mp.workdps(DPS):
        ref = f(*args)
        return float(abs(mpf(got) - ref) / (EPS * condition(f, args)))


# -- mpmath references: the textbook formulas (independent of ours), limits at the exact points ------------------
def ref_forced_cos(w, W, t):
    if w == 0 and abs(W * t) < mp.mpf("1e-12"):  # 1 − cos cancels even at 60 digits: its series
        return t**2 / 2 * (1 - (W * t) ** 2 / 12)
    if w == W:
        return t * mp.sin(w * t) / (2 * w) if w else t * t / 2
    return (mp.cos(W * t) - mp.cos(w * t)) / (w**2 - W**2)


def ref_forced_sin(w, W, t):
    if w == 0:
        if abs(W * t) < mp.mpf("1e-12"):  # (Wt − sin Wt)/W² cancels even at 60 digits: its series
            return W * t**3 / 6 * (1 - (W * t) ** 2 / 20)
        return (W * t - mp.sin(W * t)) / W**2
    if w == W:
        return (mp.sin(w * t) - w * t * mp.cos(w * t)) / (2 * w**2)
    return (w * mp.sin(W * t) - W * mp.sin(w * t)) / (w * (w**2 - W**2))


def ref_velocity(ref):
    return lambda w, W, t: mp.diff(lambda s: ref(w, W, s), t)


def ref_damped(i):
    """The i-th field of FreeResponse for ``ẍ + 2ζω ẋ + ω² x = 0``."""

    def f(w, z, t):
        a = z * w
        bsq = w * w * (z - 1) * (z + 1)
        e = mp.exp(-a * t)
        if bsq == 0:
            g = (e * (1 + a * t), e * t, -w * w * e * t, e * (1 - a * t))
        else:
            b = mp.sqrt(bsq) if bsq > 0 else mp.mpc(0, 1) * mp.sqrt(-bsq)
            C, S = mp.cosh(b * t), mp.sinh(b * t) / b
            g1 = mp.re(e * S)
            g = (mp.re(e * (C + a * S)), g1, -w * w * g1, mp.re(e * (C - a * S)))
        return g[i]

    return f


# -- elementary kernels ---------------------------------------------------------------------------------------
def test_omega_from_omega2_clips_roundoff_to_zero():
    w = omega_from_omega2(np.array([-1e-30, 0.0, 4.0, -0.0]))
    assert np.all(np.isfinite(w))
    np.testing.assert_allclose(w, [0.0, 0.0, 2.0, 0.0], rtol=0, atol=0)


def test_sinc_sinhc_are_one_at_zero_and_accurate_near_it():
    x = np.array([0.0, 5e-324, 1e-300, 1e-15, 1e-8, 1e-3, 0.7, 30.0])
    s, sh = sinc(x), sinhc(x)
    assert s[0] == 1.0 and sh[0] == 1.0
    with mp.workdps(DPS):
        for xi, si, shi in zip(x[1:], s[1:], sh[1:]):
            X = mpf(xi)
            assert abs(mpf(si) - mp.sin(X) / X) <= 2 * EPS * abs(mp.sin(X) / X)
            assert abs(mpf(shi) - mp.sinh(X) / X) <= 2 * EPS * abs(mp.sinh(X) / X)


def test_tsinc_is_t_at_zero_frequency():
    t = np.array([0.0, 1.0, 1e6])
    np.testing.assert_allclose(tsinc(0.0, t), t, rtol=0, atol=0)


# -- resonant forcing ---------------------------------------------------------------------------------------------
FORCED_OMEGA = [1.0, 1e4]
FORCED_TIMES = [1e-5, 0.3, 1.999, 2.001, 7.3, 150.0]  # as ω·t; 2 is the series/closed-form switch


@pytest.mark.parametrize("omega,rel", list(itertools.product(FORCED_OMEGA, NEAR)))
def test_resonant_forcing_matches_mpmath(omega, rel):
    W = omega * (1.0 + rel)
    t = np.array(FORCED_TIMES) / omega
    xc, vc = undamped_forced_cos(omega, W, t)
    xs, vs = undamped_forced_sin(omega, W, t)
    worst = 0.0
    for j, tj in enumerate(t):
        args = (mpf(omega), mpf(W), mpf(tj))
        for got, ref in ((xc[j], ref_forced_cos), (vc[j], ref_velocity(ref_forced_cos)),
                         (xs[j], ref_forced_sin), (vs[j], ref_velocity(ref_forced_sin))):
            worst = max(worst, scaled_error(got, ref, args))
    assert worst <= C_TOL, worst


@pytest.mark.parametrize("ratio", [1e-3, 0.3, 0.5, 0.5000001, 1.9999999, 2.0, 2.5, 1e3])
def test_forcing_far_from_resonance_and_across_branch_switches(ratio):
    omega = 3.0
    W = omega * ratio
    t = np.array([1e-4, 0.5, 0.66, 0.67, 2.0, 40.0]) / omega
    xs, _ = undamped_forced_sin(omega, W, t)
    xc, _ = undamped_forced_cos(omega, W, t)
    for j, tj in enumerate(t):
        args = (mpf(omega), mpf(W), mpf(tj))
        assert scaled_error(xs[j], ref_forced_sin, args) <= C_TOL
        assert scaled_error(xc[j], ref_forced_cos, args) <= C_TOL


@pytest.mark.parametrize("W", [0.0, 1e-300, 1e-8, 1.0, 50.0])
def test_forcing_a_rigid_mode(W):
    """ω = 0 (a free piece driven by a harmonic force): x = (Ωt − sin Ωt)/Ω², (1 − cos Ωt)/Ω²."""
    t = np.array([0.0, 1e-3, 1.0, 1e3])
    xs, vs = undamped_forced_sin(0.0, W, t)
    xc, vc = undamped_forced_cos(0.0, W, t)
    assert np.all(np.isfinite([xs, vs, xc, vc]))
    if W == 0.0:  # a constant unit force: x = t²/2, and no force at all
        np.testing.assert_allclose(xc, t**2 / 2, rtol=1e-15, atol=0)
        np.testing.assert_allclose(vc, t, rtol=1e-15, atol=0)
        assert not np.any(xs) and not np.any(vs)
        return
    for j, tj in enumerate(t[1:], start=1):
        args = (mp.mpf(0), mpf(W), mpf(tj))
        assert scaled_error(xs[j], ref_forced_sin, args) <= C_TOL
        assert scaled_error(xc[j], ref_forced_cos, args) <= C_TOL


def test_forcing_is_odd_and_even_in_the_drive_frequency():
    t = np.linspace(0.0, 20.0, 7)
    xs_p, vs_p = undamped_forced_sin(1.3, 0.9, t)
    xs_m, vs_m = undamped_forced_sin(1.3, -0.9, t)
    np.testing.assert_allclose(xs_m, -xs_p, rtol=1e-15)
    np.testing.assert_allclose(vs_m, -vs_p, rtol=1e-15)
    np.testing.assert_allclose(undamped_forced_cos(1.3, -0.9, t)[0], undamped_forced_cos(1.3, 0.9, t)[0],
                               rtol=1e-15)


def test_textbook_resonance_formula_fails_where_ours_does_not():
    """The tolerance can fail: the naive quotient loses ~|log10 rel| digits near resonance."""
    omega, t = 1.0, 7.3
    W = omega * (1 + 1e-12)
    naive = (np.cos(W * t) - np.cos(omega * t)) / (omega**2 - W**2)
    args = (mpf(omega), mpf(W), mpf(t))
    assert scaled_error(naive, ref_forced_cos, args) > 1e3 * C_TOL
    assert scaled_error(undamped_forced_cos(omega, W, t)[0], ref_forced_cos, args) <= C_TOL


# -- damped free response ----------------------------------------------------------------------------------------
ZETAS = [0.0, 0.1, 1.5, 10.0, 1e4, 1e8] + [1.0 + r for r in NEAR]
DAMPED_TIMES = [1e-6, 0.01, 0.5, 1.0, 3.0, 30.0, 300.0]  # as ω·t


@pytest.mark.parametrize("omega,zeta", list(itertools.product([1.0, 1e5], ZETAS)))
def test_damped_free_response_matches_mpmath(omega, zeta):
    t = np.array(DAMPED_TIMES) / omega
    got = damped_free(omega, zeta, t)
    assert isinstance(got, FreeResponse)
    worst = 0.0
    for j, tj in enumerate(t):
        args = (mpf(omega), mpf(zeta), mpf(tj))
        for i in range(4):
            worst = max(worst, scaled_error(got[i][j], ref_damped(i), args))
    assert worst <= C_TOL, worst


def test_critical_damping_is_continuous_from_both_sides():
    w = 2.0
    t = np.linspace(0.0, 40.0, 81)
    at = damped_free(w, 1.0, t)
    envelope = np.exp(-w * t) * (1 + w * t) * (1 + w * w)  # bounds |g0|, |g1|, |ġ0|, |ġ1| at ζ = 1
    for rel in (1e-15, -1e-15, 1e-12, -1e-12):
        near = damped_free(w, 1.0 + rel, t)
        for a, b in zip(at, near):
            # the response moves by O(rel·(ωt)²); no jump from a branch switch
            assert np.all(np.abs(a - b) <= (4 * EPS + 10 * abs(rel) * (1 + (w * t) ** 2)) * envelope)


def test_strong_overdamping_keeps_the_slow_root():
    """ζ = 1e8: after the fast transient x decays at λ_s = −ω/(2ζ) to full relative accuracy.

    The textbook root −ζω + ω√(ζ²−1) is exactly 0 in float64 here (no decay at all)."""
    omega, zeta = 1.0, 1e8
    naive_root = -zeta * omega + omega * np.sqrt(zeta**2 - 1)
    assert naive_root == 0.0
    t = np.array([1e-3, 1.0, 1e6, 1e8, 1e9])
    g = damped_free(omega, zeta, t)
    with mp.workdps(DPS):
        a, w = mpf(zeta) * mpf(omega), mpf(omega)
        b = mp.sqrt(a * a - w * w)
        slow = -w * w / (a + b)
        for j, tj in enumerate(t):
            want = (a + b) * mp.exp(slow * mpf(tj)) / (2 * b) - (a - b) * mp.exp(-(a + b) * mpf(tj)) / (2 * b)
            assert abs(mpf(g.g0[j]) - want) <= 8 * EPS * (1 + abs(slow * mpf(tj))) * abs(want)


def test_undamped_limit_is_cos_and_tsinc():
    t = np.linspace(0.0, 50.0, 11)
    g = damped_free(1.7, 0.0, t)
    np.testing.assert_allclose(g.g0, np.cos(1.7 * t), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(g.g1, tsinc(1.7, t), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(g.dg1, np.cos(1.7 * t), rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(g.dg0, -1.7**2 * tsinc(1.7, t), rtol=1e-14, atol=1e-15)


@pytest.mark.parametrize("gamma", [0.0, 1e-9, 0.4, 1e6])
def test_damped_rigid_mode(gamma):
    """ω = 0 with damping rate 2γ (mass-proportional damping of a free piece)."""
    t = np.array([0.0, 1e-3, 1.0, 1e3])
    g = damped_free_rate(0.0, gamma, t)
    with mp.workdps(DPS):
        for j, tj in enumerate(t):
            T, G = mpf(tj), mpf(gamma)
            g1 = (1 - mp.exp(-2 * G * T)) / (2 * G) if gamma else T
            dg1 = mp.exp(-2 * G * T)
            assert abs(mpf(g.g0[j]) - 1) <= 4 * EPS
            assert abs(mpf(g.g1[j]) - g1) <= 8 * EPS * (abs(g1) + 2 * G * T * abs(dg1) * T)
            # (an absolute floor for e^{-2γt} below the smallest normal float)
            assert abs(mpf(g.dg1[j]) - dg1) <= 8 * EPS * (1 + 2 * G * T) * dg1 + 1e-300
            assert g.dg0[j] == 0.0


def test_rate_and_ratio_forms_agree():
    w, z = 3.0, np.array([0.0, 0.2, 1.0, 7.0])
    t = np.linspace(0.0, 5.0, 9)[:, None]
    a, b = damped_free(w, z, t), damped_free_rate(w, z * w, t)
    for x, y in zip(a, b):
        # ζ ≠ 1: b² from (ζ−1)(ζ+1)ω² or (γ−ω)(γ+ω) differ by rounding only
        np.testing.assert_allclose(x, y, rtol=1e-13, atol=1e-14 * np.max(np.abs(x)))


def test_no_warnings_and_no_nan_on_a_broadcast_grid():
    w = np.array([0.0, 1e-300, 1e-8, 1.0, 1e8])[:, None, None]
    z = np.array([0.0, 1.0 - 1e-15, 1.0, 1.0 + 1e-15, 1e8])[None, :, None]
    t = np.array([0.0, 1e-9, 1.0, 1e9])[None, None, :]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        outs = list(damped_free(w, z, t)) + list(undamped_forced_cos(w, z, t)) + list(undamped_forced_sin(w, z, t))
    for o in outs:
        assert o.shape == (5, 5, 4)
        assert np.all(np.isfinite(o))
