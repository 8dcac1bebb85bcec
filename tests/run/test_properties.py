"""Property-based tests over random scenes built directly as arrays (no SymPy).

Scenes: N from 1 to 60; chains with random cuts (disconnected pieces), extra
springs (cycles, duplicates), rings, springs to walls; masses and
stiffnesses log-uniform over 16 decades (1e-8 … 1e8).

Tolerances are stated where they are used, each a small multiple of the
roundoff scale of the quantity tested (ε times the size of the terms that
are summed), so a wrong sign, a lost factor or a leaking mode fails them.
Failing examples found by hypothesis are kept in ``tests/regressions/``.
"""

from __future__ import annotations

import numpy as np
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from springchain.numeric.run.driver import integrate
from helpers import free_pieces
from springchain.numeric.integrators import VelocityVerlet
from springchain.numeric.integrators.base import Problem
from springchain.numeric.exact.modal import ModalSolution
from springchain.numeric.modes.spectrum import incidence, spectrum, stiffness_matrix

EPS = np.finfo(float).eps


# -- scenes ------------------------------------------------------------------------------------------------------
@st.composite
def scenes(draw, max_n: int = 60, decades: float = 16.0):
    """(masses (N,), ends (S, 2) with -1 = wall, k (S,))."""
    n = draw(st.integers(1, max_n))
    links = draw(st.lists(st.booleans(), min_size=n - 1, max_size=n - 1))
    ends = [[i, i + 1] for i, keep in enumerate(links) if keep]
    if n > 2 and draw(st.booleans()):
        ends.append([n - 1, 0])  # close a ring
    if n > 1:
        pair = st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)).filter(lambda p: p[0] != p[1])
        ends += [list(p) for p in draw(st.lists(pair, max_size=4))]
    walls = draw(st.lists(st.integers(0, n - 1), max_size=3))
    ends += [[-1, i] if j % 2 else [i, -1] for j, i in enumerate(walls)]
    half = decades / 2
    exps = st.floats(-half, half, allow_nan=False, allow_infinity=False)
    masses = 10.0 ** np.array(draw(st.lists(exps, min_size=n, max_size=n)))
    k = 10.0 ** np.array(draw(st.lists(exps, min_size=len(ends), max_size=len(ends))))
    return masses, np.array(ends, dtype=int).reshape(-1, 2), k


def states(n: int, seed: int):
    rng = np.random.default_rng(seed)
    return rng.normal(size=n), rng.normal(size=n)


def free_piece_list(n, ends):
    """Free connected pieces by an independent union-find."""
    return [np.array(g) for g in free_pieces(n, ends)]


def spring_forces(ends, k, x):
    """``K x`` through the springs: ``Bᵀ (k ⊙ B x)``; x shape (N, ...)."""
    B = incidence(x.shape[0], ends)
    return B.T @ (k.reshape((-1,) + (1,) * (x.ndim - 1)) * (B @ x))


def extension_scale(ends, k, x):
    """``Σ_s k_s |Δx_s| (|x_a| + |x_b|)``: the rounding scale of the spring energy of float positions."""
    B = incidence(x.shape[0], ends)
    return (k[:, None] * np.abs(B @ x) * (np.abs(B) @ np.abs(x))).sum(axis=0)


def energy(masses, ends, k, x, v):
    """½ vᵀMv + ½ Σ k Δx²; x, v shape (N, B) -> (B,)."""
    d = incidence(x.shape[0], ends) @ x
    return 0.5 * (masses[:, None] * v * v).sum(axis=0) + 0.5 * (k[:, None] * d * d).sum(axis=0)


# -- the operator and its modes ------------------------------------------------------------------------------------
@given(scenes())
@example((np.ones(9), np.array([[7, 8], [0, 1], [0, 1], [1, 0]]), np.array([1.0, 1.0, 1.07460783, 0.1])))
def test_stiffness_is_symmetric_positive_semidefinite(scene):
    masses, ends, k = scene
    K = stiffness_matrix(masses.size, ends, k)
    np.testing.assert_array_equal(K, K.T)
    lam = np.linalg.eigvalsh(K)
    assert lam.min() >= -4 * masses.size * EPS * max(np.abs(lam).max(), np.finfo(float).tiny)


@given(scenes())
def test_modes_structure_and_orthonormality(scene):
    masses, ends, k = scene
    n = masses.size
    spec = spectrum(masses, ends, k)
    pieces = free_piece_list(n, ends)
    r = len(pieces)
    # ω² ≥ 0, ascending, finite; exactly one exact zero per free piece
    assert np.all(np.isfinite(spec.omega)) and np.all(spec.omega2 >= 0)
    assert np.all(np.diff(spec.omega) >= 0)
    assert spec.rigid == r and not np.any(spec.omega[:r]) and np.all(spec.omega[r:] > 0)
    # rigid shapes: a uniform translation of one piece each
    supports = sorted(tuple(np.flatnonzero(spec.shapes[:, j])) for j in range(r))
    assert supports == sorted(tuple(p) for p in pieces)
    for j in range(r):
        col = spec.shapes[:, j][spec.shapes[:, j] != 0]
        np.testing.assert_allclose(col, col[0], rtol=4 * EPS)
    # M-orthonormal physical shapes (relative to the identity: roundoff of n-term dot products)
    S = spec.shapes
    gram = S.T @ (masses[:, None] * S)
    assert np.max(np.abs(gram - np.eye(n))) <= 8 * n * EPS
    # residual of the eigen-equation, relative to ‖D‖ (the best any float64 method can promise normwise)
    assert spec.residual(stiffness_matrix(n, ends, k)) <= 8 * n * EPS


# -- the exact solution -------------------------------------------------------------------------------------------
TIMES = np.array([0.0, 0.37, 12.5, 1e3])


@given(scenes(), st.integers(0, 2**16))
def test_exact_solution_satisfies_the_equations_of_motion(scene, seed):
    """``M ẍ + K x = 0`` with ẍ the solution's own analytic second derivative ``-Φ Ω² q``.

    Normwise in mass-weighted coordinates: ``‖M^-1/2 (M ẍ + K x)‖`` is ``‖(DV − VΛ) q‖``
    plus the rounding of the sums, at most ``c·n·ε·ω²_max·‖M^1/2 x‖`` (and of ``‖M^1/2 ẍ‖``)."""
    masses, ends, k = scene
    n = masses.size
    spec = spectrum(masses, ends, k)
    x0, v0 = states(n, seed)
    sol = ModalSolution.from_initial(spec, x0, v0)
    x, _ = sol.at(TIMES)
    a = sol.acceleration_at(TIMES)
    root_m = np.sqrt(masses)
    for xt, at in zip(x, a):
        r = masses * at + spring_forces(ends, k, xt)
        lhs = np.linalg.norm(r / root_m)
        scale = spec.omega_max**2 * np.linalg.norm(root_m * xt) + np.linalg.norm(root_m * at)
        assert lhs <= 16 * n * EPS * scale + np.finfo(float).tiny


@given(scenes(), st.integers(0, 2**16))
def test_exact_solution_reproduces_the_initial_state(scene, seed):
    masses, ends, k = scene
    n = masses.size
    x0, v0 = states(n, seed)
    x, v = ModalSolution.from_initial(spectrum(masses, ends, k), x0, v0).at(0.0)
    root_m = np.sqrt(masses)
    # mass-weighted: the transform to modal coordinates and back is orthogonal
    assert np.linalg.norm(root_m * (x - x0)) <= 8 * n * EPS * np.linalg.norm(root_m * x0)
    assert np.linalg.norm(root_m * (v - v0)) <= 8 * n * EPS * np.linalg.norm(root_m * v0)


@given(scenes(), st.integers(0, 2**16))
@example((np.array([10.0, 1e-5, 1.0, 1.0]), np.array([[0, 1], [0, -1]]), np.array([1e7, 1.0])), 0)
def test_momentum_of_free_pieces_and_energy_are_conserved(scene, seed):
    masses, ends, k = scene
    n = masses.size
    x0, v0 = states(n, seed)
    sol = ModalSolution.from_initial(spectrum(masses, ends, k), x0, v0)
    x, v = sol.at(TIMES)
    # momentum of every free piece, to the roundoff of Σ m v (ε·Σ m|v|)
    for piece in free_piece_list(n, ends):
        m = masses[piece]
        p = v[:, piece] @ m
        assert np.all(np.abs(p - p[0]) <= 8 * n * EPS * (np.abs(v[:, piece]) @ m))
    # energy through the springs. Rounding scales: the terms themselves; float positions in the
    # extensions (a drift of |x| moves a stiff spring's Δx by ε|x|); and the normwise accuracy of the
    # modes, ‖VᵀDV − Λ‖ ≲ ε ω²_max, coupling elastic modes of amplitudes a_j = √(q0² + (q̇0/ω)²)
    spec = sol.spectrum
    el = slice(spec.rigid, None)
    amp2 = np.sum(sol.q0[el] ** 2 + (sol.p0[el] / spec.omega[el]) ** 2)
    e = energy(masses, ends, k, x.T, v.T)
    tol = 16 * n * EPS * (e[0] + extension_scale(ends, k, x.T) + (masses[:, None] * v.T**2).sum(axis=0)
                          + spec.omega_max**2 * amp2)
    assert np.all(np.abs(e - e[0]) <= tol + np.finfo(float).tiny)
    assert abs(e[0] - sol.energy) <= tol[0] + np.finfo(float).tiny


# -- Verlet converges to it ----------------------------------------------------------------------------------------
@settings(max_examples=15)
@given(scenes(max_n=8, decades=4.0), st.integers(0, 2**16))
def test_verlet_converges_to_the_exact_solution_at_order_two(scene, seed):
    masses, ends, k = scene
    n = masses.size
    spec = spectrum(masses, ends, k)
    assume(spec.omega_max > 0)
    x0, v0 = states(n, seed)
    minv = 1.0 / masses[:, None]
    problem = Problem(lambda x: -spring_forces(ends, k, x) * minv)
    t_end = 10.0 / spec.omega_max
    exact = ModalSolution.from_initial(spec, x0, v0)
    errors, momenta = [], []
    for steps in (200, 400):  # ω_max·h = 0.05, 0.025: well inside the stability limit 2
        traj = integrate(VelocityVerlet(), problem, x0, v0, t_end / steps, steps, record_every=steps // 4)
        x_ref, _ = exact.at(traj.t)
        root_m = np.sqrt(masses)
        errors.append(np.max(np.linalg.norm(root_m * (traj.x[:, :, 0] - x_ref), axis=1)))
        momenta.append(traj.v[:, :, 0])
    # the error must be visible above roundoff for a slope to mean anything
    scale = np.linalg.norm(np.sqrt(masses) * x0) + np.linalg.norm(np.sqrt(masses) * v0) / spec.omega_max
    assume(errors[1] > 1e-10 * scale)
    slope = np.log2(errors[0] / errors[1])
    assert 1.8 <= slope <= 2.2, (slope, errors)
    # Verlet conserves the momentum of every free piece too
    for piece in free_piece_list(n, ends):
        p = momenta[1][:, piece] @ masses[piece]
        assert np.all(np.abs(p - p[0]) <= 64 * n * EPS * (np.abs(momenta[1][:, piece]) @ masses[piece]).max())
