"""Long runs: the modal solution at t = 1e6 and Verlet's energy over many steps.

* The modal solution conserves momentum and moves every free piece's centre
  of mass exactly as ``x_cm0 + v_cm·t`` to roundoff at t = 1e6, with mass and
  stiffness ratios of 1e8 (the elastic modes are orthogonal to the rigid
  ones to roundoff, so they carry neither).
* Displacement coordinates: a drift of 1e6 does not enter a spring extension
  beyond the roundoff of the position itself.
* Verlet's energy error stays inside its theoretical band
  ``(ωh)²/(4 − (ωh)²)`` and its exactly conserved modified energy moves by
  roundoff only (``slow``: 1e5 steps × ``SPRINGCHAIN_SLOW_BUDGET``).
* ``verlet-kahan`` (kick–drift–kick with compensated summation) follows
  ``verlet`` to roundoff, has order 2, and has less roundoff drift at small ω·h.
"""

from __future__ import annotations


import numpy as np
import pytest

from springchain.numeric.run.driver import integrate
from springchain.numeric.integrators import VelocityVerlet
from springchain.numeric.integrators.base import Problem
from springchain.numeric.integrators.verlet_compensated import CompensatedVerlet
from springchain.numeric.exact.modal import ModalSolution
from springchain.numeric.modes.spectrum import free_pieces, spectrum, stiffness_matrix

EPS = np.finfo(float).eps
from helpers import SLOW_BUDGET as BUDGET  # noqa: E402


def graded_free_scene():
    """Two free pieces (a chain and a ring) and a walled chain; masses 1e4 / 1e-4, springs 1e8 / 1."""
    masses = np.array([1e4, 1e-4, 1e4, 1e-4, 1e4, 1e-4, 1e4, 1e-4, 1.0, 1e4, 1e-4])
    ends = np.array([[0, 1], [1, 2], [2, 3], [3, 4],  # chain piece 0..4
                     [5, 6], [6, 7], [7, 5],  # ring piece 5..7
                     [-1, 8], [8, 9], [9, 10]])  # walled piece
    k = np.array([1e8, 1.0, 1e8, 1.0, 1.0, 1e8, 1e8, 1e8, 1.0, 1e8])
    return masses, ends, k


def initial_state(masses, seed=0):
    rng = np.random.default_rng(seed)
    n = masses.size
    return rng.normal(size=n), rng.normal(size=n) + 3.0  # a net drift of every free piece


# -- the modal solution at t = 1e6 ---------------------------------------------------------------------------------
T_LONG = np.concatenate([[0.0], np.geomspace(1.0, 1e6, 13)])


def test_momentum_of_each_free_piece_is_conserved_to_roundoff():
    masses, ends, k = graded_free_scene()
    x0, v0 = initial_state(masses)
    _, v = ModalSolution.from_initial(spectrum(masses, ends, k), x0, v0).at(T_LONG)
    for piece in free_pieces(masses.size, ends):
        m = masses[piece]
        p = v[:, piece] @ m
        scale = np.abs(v[:, piece]) @ m  # Σ m|v|: the roundoff scale of the sum itself
        assert np.all(np.abs(p - p[0]) <= 8 * piece.size * EPS * scale), np.max(np.abs(p - p[0]) / scale)


def test_rigid_drift_is_exact_at_one_million_seconds():
    masses, ends, k = graded_free_scene()
    x0, v0 = initial_state(masses)
    x, _ = ModalSolution.from_initial(spectrum(masses, ends, k), x0, v0).at(T_LONG)
    for piece in free_pieces(masses.size, ends):
        m = masses[piece]
        M = m.sum()
        want = (m @ x0[piece]) / M + (m @ v0[piece]) / M * T_LONG
        got = x[:, piece] @ m / M
        scale = np.abs(x[:, piece]) @ m / M
        assert np.all(np.abs(got - want) <= 8 * piece.size * EPS * scale), np.max(np.abs(got - want) / scale)


def test_a_drift_does_not_enter_the_spring_extensions():
    """Extensions of a piece drifting 3e6 equal those of the same motion without drift,
    to the roundoff of the positions (|x|·ε), although the stiff springs stretch by ~1e-8 only."""
    masses, ends, k = graded_free_scene()
    x0, v0 = initial_state(masses)
    spec = spectrum(masses, ends, k)
    still = v0.copy()
    for piece in free_pieces(masses.size, ends):
        still[piece] -= masses[piece] @ v0[piece] / masses[piece].sum()
    t = T_LONG[-4:]
    x_drift, _ = ModalSolution.from_initial(spec, x0, v0).at(t)
    x_still, _ = ModalSolution.from_initial(spec, x0, still).at(t)
    inner = (ends[:, 0] >= 0) & (ends[:, 1] >= 0)
    a, b = ends[inner, 0], ends[inner, 1]
    ext_drift = x_drift[:, a] - x_drift[:, b]
    ext_still = x_still[:, a] - x_still[:, b]
    pos_scale = np.max(np.abs(x_drift), axis=1, keepdims=True)
    assert np.all(np.abs(ext_drift - ext_still) <= 8 * EPS * pos_scale)


def test_modal_energy_is_constant_at_one_million_seconds():
    masses, ends, k = graded_free_scene()
    x0, v0 = initial_state(masses)
    sol = ModalSolution.from_initial(spectrum(masses, ends, k), x0, v0)
    x, v = sol.at(T_LONG)
    e = energy(masses, ends, k, x.T, v.T)
    # springs only through their extensions: each term ≥ 0; the drift (≈3e6) sets the roundoff of
    # an extension, ε·|x|, so the stiff springs' energy carries ~k·|Δx|·ε|x| of rounding
    pos = np.max(np.abs(x), axis=1)
    spring_rounding = np.tensordot(k, np.abs(extensions(ends, x.T)), axes=(0, 0)) * 4 * EPS * pos
    assert np.all(np.abs(e - e[0]) <= 64 * EPS * e[0] + spring_rounding)
    np.testing.assert_allclose(e[0], sol.energy, rtol=1e-12)


# -- Verlet over many steps -----------------------------------------------------------------------------------------
def extensions(ends, x):
    """Spring extensions ``x_a − x_b`` (a wall end is 0); x shape (N, ...) -> (S, ...)."""
    a, b = ends[:, 0], ends[:, 1]
    shape = (-1,) + (1,) * (x.ndim - 1)
    xa = np.where((a >= 0).reshape(shape), x[np.maximum(a, 0)], 0.0)
    xb = np.where((b >= 0).reshape(shape), x[np.maximum(b, 0)], 0.0)
    return xa - xb


def energy(masses, ends, k, x, v):
    """½ vᵀMv + ½ Σ k Δx², through spring extensions; x, v shape (N, ...) -> (...)."""
    d = extensions(ends, x)
    return 0.5 * np.tensordot(masses, v * v, axes=(0, 0)) + 0.5 * np.tensordot(k, d * d, axes=(0, 0))


def modified_energy(masses, K, h, x, v):
    """Verlet's exactly conserved quadratic invariant on a linear chain:
    ``½ vᵀMv + ½ xᵀ(K − h² K M⁻¹ K / 4) x``; x, v shape (N, B) -> (B,)."""
    Kx = K @ x
    return 0.5 * np.sum(masses[:, None] * v * v, axis=0) + 0.5 * np.sum(x * Kx, axis=0) \
        - (h * h / 8) * np.sum(Kx * Kx / masses[:, None], axis=0)


def small_graded_chain():
    rng = np.random.default_rng(5)
    n = 6
    masses = 10 ** rng.uniform(-1, 1, n)
    ends = np.array([[-1, 0]] + [[i, i + 1] for i in range(n - 1)] + [[n - 1, -1]])
    k = 10 ** rng.uniform(-1, 1, n + 1)
    return masses, ends, k


def linear_problem(masses, ends, k):
    K = stiffness_matrix(masses.size, ends, k)
    minv = 1.0 / masses[:, None]
    return Problem(lambda x: -(K @ x) * minv), K


def run_energy(integrator, masses, ends, k, omega_h, steps, batch=8):
    problem, K = linear_problem(masses, ends, k)
    h = omega_h / spectrum(masses, ends, k).omega_max
    rng = np.random.default_rng(11)
    x0, v0 = rng.normal(size=(masses.size, batch)), rng.normal(size=(masses.size, batch))
    traj = integrate(integrator, problem, x0, v0, h, steps, record_every=max(steps // 500, 1))
    x, v = np.moveaxis(traj.x, 0, -1), np.moveaxis(traj.v, 0, -1)  # (N, B, S)
    e = energy(masses, ends, k, x, v)
    e_mod = np.stack([modified_energy(masses, K, h, traj.x[s], traj.v[s]) for s in range(traj.t.size)], axis=-1)
    return e, e_mod


@pytest.mark.slow
@pytest.mark.parametrize("integrator", [VelocityVerlet(), CompensatedVerlet()], ids=lambda i: i.name)
def test_verlet_energy_stays_in_its_band_over_a_long_run(integrator):
    masses, ends, k = small_graded_chain()
    omega_h = 0.5
    steps = int(1e5 * BUDGET)
    e, e_mod = run_energy(integrator, masses, ends, k, omega_h, steps)
    band = omega_h**2 / (4 - omega_h**2)
    rel = np.abs(e - e[:, :1]) / e[:, :1]
    assert np.max(rel) <= band * (1 + 1e-9)
    # the energy error oscillates, it does not grow: the last tenth is no worse than the first
    tenth = rel.shape[1] // 10
    assert np.max(rel[:, -tenth:]) <= 1.5 * np.max(rel[:, :tenth]) + 1e-12
    # the modified energy moves by roundoff only (at most ~ε per step even if every rounding had one sign)
    drift = np.max(np.abs(e_mod - e_mod[:, :1]) / e_mod[:, :1])
    assert drift <= 2 * EPS * steps + 1e-14, drift


@pytest.mark.slow
def test_compensation_pays_at_small_steps():
    """At ω·h = 0.01 the compensated kick–drift–kick form keeps the modified energy
    within a few ulps where plain Verlet random-walks (measured 1.5e-15 vs 3e-13 over 1e7 steps)."""
    masses, ends, k = small_graded_chain()
    steps = int(1e5 * BUDGET)
    _, plain = run_energy(VelocityVerlet(), masses, ends, k, 0.01, steps, batch=16)
    _, comp = run_energy(CompensatedVerlet(), masses, ends, k, 0.01, steps, batch=16)
    d_plain = np.max(np.abs(plain - plain[:, :1]) / plain[:, :1])
    d_comp = np.max(np.abs(comp - comp[:, :1]) / comp[:, :1])
    assert d_comp <= 64 * EPS * (1 + np.sqrt(steps) / 100), d_comp
    assert d_comp <= d_plain, (d_comp, d_plain)


# -- verlet-kahan is Verlet -----------------------------------------------------------------------------------------
def test_compensated_verlet_follows_verlet_to_roundoff():
    masses, ends, k = small_graded_chain()
    problem, _ = linear_problem(masses, ends, k)
    h = 0.3 / spectrum(masses, ends, k).omega_max
    rng = np.random.default_rng(2)
    x0, v0 = rng.normal(size=masses.size), rng.normal(size=masses.size)
    a = integrate(VelocityVerlet(), problem, x0, v0, h, 2000, record_every=100)
    b = integrate(CompensatedVerlet(), problem, x0, v0, h, 2000, record_every=100)
    scale = np.max(np.abs(a.x))
    assert np.max(np.abs(a.x - b.x)) <= 1e-11 * scale
    assert b.force_evals == a.force_evals


def test_compensated_verlet_is_second_order():
    masses, ends, k = small_graded_chain()
    problem, _ = linear_problem(masses, ends, k)
    spec = spectrum(masses, ends, k)
    rng = np.random.default_rng(4)
    x0, v0 = rng.normal(size=masses.size), rng.normal(size=masses.size)
    t_end = 40.0 / spec.omega_max
    exact = ModalSolution.from_initial(spec, x0, v0)
    errors = []
    for steps in (200, 400, 800):
        traj = integrate(CompensatedVerlet(), problem, x0, v0, t_end / steps, steps, record_every=steps // 4)
        x_ref, _ = exact.at(traj.t)
        errors.append(np.max(np.abs(traj.x[:, :, 0] - x_ref)))
    slopes = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(slopes - 2.0) <= 0.1), slopes


def test_compensation_carries_restart_from_a_foreign_state():
    """Kernel purity: a step from a state it did not return equals a fresh start."""
    masses, ends, k = small_graded_chain()
    problem, _ = linear_problem(masses, ends, k)
    kern = CompensatedVerlet().kernel(problem, 0.01)
    x = np.ones((masses.size, 1))
    v = np.zeros_like(x)
    a = problem.acceleration(x)
    for i in range(5):
        x, v, a = kern(x, v, a, i)
    fresh = CompensatedVerlet().kernel(problem, 0.01)(x.copy(), v.copy(), a, 5)
    again = kern(x.copy(), v.copy(), a, 5)
    for p, q in zip(fresh, again):
        np.testing.assert_array_equal(p, q)
