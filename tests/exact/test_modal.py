"""The exact modal solution (numeric.exact.modal): rigid-body drift, conservation, the ODE itself,
and the naive divide-by-ω formula going wrong where ours does not."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from springchain.numeric.exact.modal import ModalSolution, tsinc
from springchain.numeric.run.exact import spectrum_of as system_spectrum
from springchain.numeric.modes.spectrum import spectrum
from springchain.numeric.system import System


@pytest.fixture(scope="module")
def seed_solution(seed_system, reference):
    return ModalSolution.from_initial(system_spectrum(seed_system, "svd"), reference["x0"], reference["v0"])


def _cm(system, x):
    """Centre of mass of x with shape (..., N)."""
    m = system.masses
    return x @ m / m.sum()


# -- rigid-body drift ---------------------------------------------------------------------------
def test_rigid_body_drift_is_exact(seed_system, seed_solution, reference):
    m = seed_system.masses
    x_cm0 = m @ reference["x0"] / m.sum()
    v_cm = m @ reference["v0"] / m.sum()
    t = np.concatenate([np.linspace(0, 100, 11), np.geomspace(1e2, 1e6, 9)])
    x, v = seed_solution.at(t)
    assert x.shape == (t.size, 3) and v.shape == (t.size, 3)
    exact = x_cm0 + v_cm * t
    # the elastic modes contribute nothing to the centre of mass (M-orthogonal to translation)
    # so the only error is roundoff relative to the larger of |x_cm| and the oscillation amplitude
    amplitude = 3.0
    err = np.abs(_cm(seed_system, x) - exact)
    assert np.all(err <= 1e-12 * np.maximum(np.abs(exact), amplitude)), err.max()
    np.testing.assert_allclose(_cm(seed_system, v), v_cm, rtol=1e-12, atol=1e-12 * amplitude)
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(v))


def test_rigid_drift_at_the_end_of_the_reference_run(seed_system, seed_solution, reference):
    t_end = reference["dt"] * reference["steps"]
    m = seed_system.masses
    x, _ = seed_solution.at(t_end)
    want = (m @ reference["x0"] + m @ reference["v0"] * t_end) / m.sum()
    assert abs(_cm(seed_system, x) - want) <= 1e-13 * max(abs(want), 1.0)


def test_momentum_and_energy_are_conserved(seed_system, seed_solution):
    t = np.linspace(0.0, 1000.0, 2001)
    x, v = seed_solution.at(t)
    p = seed_system.momentum(v.T)
    assert np.max(np.abs(p - p[0])) <= 1e-12 * max(abs(p[0]), np.abs(seed_system.masses[:, None] * v.T).max())
    e = seed_system.energy(x.T, v.T)
    assert np.max(np.abs(e - e[0])) <= 1e-12 * e[0]


def test_initial_state_is_reproduced(seed_solution, reference):
    x, v = seed_solution.at(0.0)
    np.testing.assert_allclose(x, reference["x0"], rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(v, reference["v0"], rtol=1e-14, atol=1e-15)


def test_tsinc_is_finite_and_exact_at_zero():
    t = np.array([0.0, 1.0, 1e6])
    np.testing.assert_array_equal(tsinc(np.zeros(3), t), t)
    w = np.array([1e-300, 1e-8, 2.0])
    np.testing.assert_allclose(tsinc(w, 1.5), np.sin(w * 1.5) / w, rtol=1e-14)


# -- the ODE ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("t", [0.0, 0.37, 5.0, 123.456, 999.9])
def test_modal_solution_satisfies_the_ode(seed_system, seed_solution, t):
    h = 1e-3
    x, v = seed_solution.at(np.array([t - h, t, t + h]))
    second = (x[2] - 2 * x[1] + x[0]) / h**2
    a = seed_system.acceleration(x[1])
    # truncation ~ h²/12 ω⁴ |x| ~ 1e-7; roundoff ~ eps |x| / h² ~ 1e-9 (|x| grows with the drift)
    scale = max(np.abs(x[1]).max(), 1.0)
    np.testing.assert_allclose(second, a, rtol=0, atol=1e-5 * scale)
    np.testing.assert_allclose((x[2] - x[0]) / (2 * h), v[1], rtol=0, atol=1e-6 * scale)
    # and velocity differentiates to the acceleration
    np.testing.assert_allclose((v[2] - v[0]) / (2 * h), a, rtol=0, atol=1e-6 * max(np.abs(v).max(), 1.0))


def test_batch_of_initial_states(seed_system, reference):
    spec = system_spectrum(seed_system)
    rng = np.random.default_rng(5)
    X0 = rng.normal(size=(3, 4))
    V0 = rng.normal(size=(3, 4))
    t = np.linspace(0, 20, 7)
    xb, vb = ModalSolution.from_initial(spec, X0, V0).at(t)
    assert xb.shape == (7, 3, 4)
    for j in range(4):
        xj, vj = ModalSolution.from_initial(spec, X0[:, j], V0[:, j]).at(t)
        np.testing.assert_allclose(xb[..., j], xj, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(vb[..., j], vj, rtol=1e-13, atol=1e-14)


# -- two spectrum sources -------------------------------------------------------------------------------------
def test_closed_form_and_svd_spectra_give_the_same_trajectory(seed_system, reference):
    t = np.arange(1001) * reference["dt"]
    a = ModalSolution.from_initial(system_spectrum(seed_system, "closed-form"), reference["x0"], reference["v0"])
    b = ModalSolution.from_initial(system_spectrum(seed_system, "svd"), reference["x0"], reference["v0"])
    xa, va = a.at(t)
    xb, vb = b.at(t)
    np.testing.assert_allclose(xa, xb, rtol=0, atol=1e-10)
    np.testing.assert_allclose(va, vb, rtol=0, atol=1e-10)


@pytest.mark.parametrize("params", [{"m": 0.3, "k": 7.0}, {"m": 5.0, "k": 0.02}])
def test_spectrum_sources_agree_at_other_parameters(seed_module, reference, params):
    system = System.from_module(seed_module, params)
    s_cf, s_svd = system_spectrum(system, "closed-form"), system_spectrum(system, "svd")
    np.testing.assert_allclose(s_cf.omega, s_svd.omega, rtol=1e-13, atol=0)
    assert s_cf.rigid == s_svd.rigid == 1
    # vectors orthonormal
    np.testing.assert_allclose(s_svd.vectors.T @ s_svd.vectors, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(s_cf.vectors.T @ s_cf.vectors, np.eye(3), atol=1e-14)
    t = np.linspace(0, 50, 101)
    xa, _ = ModalSolution.from_initial(s_cf, reference["x0"], reference["v0"]).at(t)
    xb, _ = ModalSolution.from_initial(s_svd, reference["x0"], reference["v0"]).at(t)
    np.testing.assert_allclose(xa, xb, rtol=0, atol=1e-10 * max(1.0, np.abs(xb).max()))


def test_svd_spectrum_has_exact_zero_for_the_rigid_mode(seed_system):
    spec = spectrum(seed_system.masses, seed_system.spring_ends, seed_system.stiffness)
    assert spec.omega[0] == 0.0 and spec.rigid == 1
    np.testing.assert_allclose(spec.omega[1:] ** 2, [1.0, 5 / 3], rtol=1e-14)


# -- the naive formula ----------------------------------------------------------------------------------------
def naive_solution(D: np.ndarray, masses: np.ndarray, x0, v0, t, w2=None):
    """The hand-written textbook formula: x(t) = M^-1/2 Σ (c1 cos ωt + c2 sin ωt) e, c2 = (e·ẏ0)/ω.

    Eigenpairs from ``numpy.linalg.eig(D)``; ``w2`` overrides the eigenvalues (to inject roundoff).
    Returns x (S, N) and the coefficients c2.
    """
    vals, E = np.linalg.eig(D)
    vals, E = np.real(vals), np.real(E)
    if w2 is not None:
        vals = np.asarray(w2, dtype=float)
    r = np.sqrt(masses)
    c1 = E.T @ (r * x0)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        w = np.sqrt(vals)
        c2 = (E.T @ (r * v0)) / w
        t = np.asarray(t, dtype=float)[:, None]
        q = c1 * np.cos(w * t) + c2 * np.sin(w * t)
    return (q @ E.T) / r, c2, vals


def test_naive_formula_goes_wrong_on_the_reference_case(seed_system, seed_module, seed_solution, reference):
    D = seed_module.dynamical_matrix(**seed_system.params)
    t = np.array([0.0, 1.0, 100.0, 1e6])
    x_naive, c2, vals = naive_solution(D, seed_system.masses, reference["x0"], reference["v0"], t)
    rigid = np.argmin(np.abs(vals))
    # eig's rigid eigenvalue is roundoff, not 0: sqrt of it is NaN (negative) or ~1e-8 (positive)
    assert abs(vals[rigid]) < 1e-12
    broken = (not np.all(np.isfinite(x_naive))) or abs(c2[rigid]) > 1e6
    assert broken, (vals, c2)
    # ours: finite and exact at the same times
    x, _ = seed_solution.at(t)
    assert np.all(np.isfinite(x))
    m = seed_system.masses
    exact_cm = (m @ reference["x0"] + m @ reference["v0"] * t) / m.sum()
    np.testing.assert_allclose(_cm(seed_system, x), exact_cm, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("roundoff", [-1.1e-16, 1.3e-16, 0.0])
def test_naive_formula_fails_for_every_roundoff_of_the_zero(seed_system, seed_module, reference, roundoff):
    """Whatever LAPACK returns for the rigid ω²: negative → NaN, tiny positive → c2 ~ 1e7 and a wrong
    drift at long times, exactly zero → 0/0."""
    D = seed_module.dynamical_matrix(**seed_system.params)
    vals = np.real(np.linalg.eigvals(D))
    rigid = np.argmin(np.abs(vals))
    vals[rigid] = roundoff
    t = np.array([1.0, 1e8])
    x_naive, c2, _ = naive_solution(D, seed_system.masses, reference["x0"], reference["v0"], t, w2=vals)
    m = seed_system.masses
    exact_cm = (m @ reference["x0"] + m @ reference["v0"] * t) / m.sum()
    if roundoff <= 0:
        assert not np.all(np.isfinite(x_naive))
    else:
        assert abs(c2[rigid]) > 1e6
        cm = _cm(seed_system, x_naive)
        assert abs(cm[-1] - exact_cm[-1]) > 0.1 * abs(exact_cm[-1])


def test_one_product_trajectory_equals_the_general_route(seed_system):
    """ModalSolution.at on a 1-D grid (one exp and one matrix product) equals the per-mode route
    to rounding, and keeps the rigid drift exact at t = 1e6."""
    from springchain.numeric.exact.modal import ModalSolution
    from springchain.numeric.run.exact import spectrum_of as system_spectrum

    spec = system_spectrum(seed_system)
    x0, v0 = np.array([0.1, -0.02, 0.03]), np.array([0.01, 0.0, -0.005])
    sol = ModalSolution.from_initial(spec, x0, v0)
    t = np.concatenate([np.arange(1001) * 0.1, [1e6]])
    x, v = sol.at(t)
    tt, q, p, _ = sol._modal(t)
    np.testing.assert_allclose(x, sol._physical(tt, q), rtol=0, atol=1e-14 * (1 + np.abs(x).max()))
    np.testing.assert_allclose(v, sol._physical(tt, p), rtol=0, atol=1e-14 * (1 + np.abs(v).max()))
    m = seed_system.masses
    vcm = float(m @ v0 / m.sum())
    assert abs(float(m @ x[-1] / m.sum()) - (float(m @ x0 / m.sum()) + vcm * 1e6)) <= 1e-12 * abs(vcm * 1e6)
