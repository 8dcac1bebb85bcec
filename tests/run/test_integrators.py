"""The integrator family (numeric.integrators) and the driver (numeric.run.driver) against exact answers.

* observed order (least-squares slope of log error against log h) equals the
  declared order, on the seed chain against the exact modal solution and on a
  nonlinear (FPU-type) chain against a tight DOP853 reference — the nonlinear
  run exercises the order conditions a linear problem cannot see;
* the optimised Blanes–Moan methods beat Yoshida's triple jump at equal cost;
* symplectic methods keep the energy error bounded over 3·10⁴ steps, RK4's grows;
* a batch of initial conditions gives the same result as one run per column;
* every method, fixed-step and adaptive, agrees with the exact solution on the
  reference scene to a tolerance that fits the method;
* the propagators are exact (expm against scipy.linalg.expm, Chebyshev with
  long steps and with a stencil acceleration), and refuse what they cannot do.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from springchain.numeric.run.driver import integrate
from springchain.numeric.run.grid import record_indices, step_grid
from springchain.numeric.errors import RunRefused
from springchain.numeric.integrators import LinearChain, Problem
from springchain.numeric.run import registry
from springchain.numeric.run.implicit import ImplicitStep
from springchain.numeric.run.protocol import Kind
from springchain.numeric.integrators.chebyshev import ChebyshevCoefficients, ChebyshevPropagator
from springchain.numeric.integrators.expm import step_matrix
from springchain.numeric.exact.modal import ModalSolution
from springchain.numeric.modes.spectrum import incidence, spectrum

INTEGRATORS, ADAPTIVE = registry.classes(Kind.STEP), registry.classes(Kind.ADAPTIVE)
FINITE_ORDER = [name for name, cls in INTEGRATORS.items() if math.isfinite(cls.order)]
PROPAGATORS = ["expm", "chebyshev"]


@pytest.fixture(scope="module")
def problem(seed_system):
    return Problem.from_system(seed_system)


@pytest.fixture(scope="module")
def exact(seed_system, reference):
    spec = spectrum(seed_system.masses, seed_system.spring_ends, seed_system.stiffness)
    return ModalSolution.from_initial(spec, reference["x0"], reference["v0"])


def random_chain(n, seed, walls=True):
    """A random linear chain: masses in [0.5, 2], springs in [0.5, 3], optional walls at both ends."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 2.0, n)
    ends = [(j, j + 1) for j in range(n - 1)]
    if walls:
        ends = [(-1, 0), *ends, (n - 1, -1)]
    ends = np.array(ends)
    k = rng.uniform(0.5, 3.0, len(ends))
    B = incidence(n, ends)
    K = B.T @ (k[:, None] * B)
    A = -K / m[:, None]
    return LinearChain(m, ends, k), A


def slope(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


# --- the tables ----------------------------------------------------------------------------------

def test_tables_name_every_method():
    assert set(INTEGRATORS) == {"verlet", "verlet-kahan", "yoshida4", "blanes-moan4", "blanes-moan6",
                                "kahan-li8", "rk4", "expm", "chebyshev", "newmark", "newmark-linear", "hht"}
    assert set(ADAPTIVE) == {"rk45", "dop853", "dop853-compiled", "lsoda", "dprkn6", "dprkn8", "dprkn12"}
    for name, cls in {**INTEGRATORS, **ADAPTIVE}.items():
        assert cls.name == name
        assert isinstance(cls.symplectic, bool) and cls.order > 0
        assert hasattr(cls, "evals_per_step")
    assert [INTEGRATORS[n].order for n in FINITE_ORDER] == [2, 2, 4, 4, 6, 8, 4, 2, 2, 2]
    assert not INTEGRATORS["rk4"].symplectic


def test_problem_from_system_carries_the_springs(seed_system, problem):
    chain = problem.linear
    assert chain is not None and chain.n == 3
    x = np.random.default_rng(1).standard_normal((3, 4))
    B = incidence(3, chain.spring_ends)
    K = B.T @ (chain.stiffness[:, None] * B)
    assert np.allclose(problem.acceleration(x), -(K @ x) / chain.masses[:, None], rtol=0, atol=1e-14)
    assert chain.omega2_bound() >= chain.spectrum().omega_max ** 2 * (1 - 1e-14)


def test_step_grid_uses_ceil_and_exact_times():
    assert step_grid(100.0, 0.1) == (pytest.approx(0.1, rel=1e-15), 1000)
    h, n = step_grid(10.0, 0.3)
    assert n == 34 and abs(n * h - 10.0) < 1e-14 and h <= 0.3
    with pytest.raises(ValueError, match="h_target"):
        step_grid(1.0, 0.0)
    assert record_indices(10, 4).tolist() == [0, 4, 8, 10]


# --- observed order ------------------------------------------------------------------------------

#: Steps per method over T = 10 on the seed: errors from ~1e-2 down to ~1e-11, above the roundoff floor.
LINEAR_STEPS = {
    "verlet": [0.2, 0.1, 0.05, 0.025],
    "verlet-kahan": [0.2, 0.1, 0.05, 0.025],
    "yoshida4": [0.4, 0.2, 0.1, 0.05],
    "blanes-moan4": [0.4, 0.2, 0.1, 0.05],
    "blanes-moan6": [0.8, 0.6, 0.4, 0.3, 0.2],
    "kahan-li8": [0.8, 0.6, 0.4, 0.3],
    "rk4": [0.4, 0.2, 0.1, 0.05],
    "newmark": [0.2, 0.1, 0.05, 0.025],
    "newmark-linear": [0.2, 0.1, 0.05, 0.025],
    "hht": [0.2, 0.1, 0.05, 0.025],
}


@pytest.mark.parametrize("name", FINITE_ORDER)
def test_observed_order_on_the_seed_chain(name, problem, exact, reference):
    T = 10.0
    xe, ve = exact.at(T)
    hs, errs = [], []
    for target in LINEAR_STEPS[name]:
        h, n = step_grid(T, target)
        tr = integrate(INTEGRATORS[name](), problem, reference["x0"], reference["v0"], h, n, record_every=n)
        hs.append(h)
        errs.append(max(np.max(np.abs(tr.x[-1, :, 0] - xe)), np.max(np.abs(tr.v[-1, :, 0] - ve))))
    assert min(errs) > 1e-12  # fit above the roundoff floor
    assert abs(slope(hs, errs) - INTEGRATORS[name].order) < 0.2, errs


M_FPU = np.array([1.0, 2.0, 0.7])


def fpu_acceleration(x):
    """Three masses between walls, springs with force d + 0.3 d² + 0.8 d³ (d: extension)."""
    pad = np.zeros((1,) + x.shape[1:])
    d = np.diff(np.concatenate([pad, x, pad]), axis=0)
    f = d + 0.3 * d**2 + 0.8 * d**3
    return (f[1:] - f[:-1]) / M_FPU.reshape((-1,) + (1,) * (x.ndim - 1))


@pytest.fixture(scope="module")
def fpu_reference():
    x0, v0, T = np.array([0.6, -0.3, 0.4]), np.array([0.1, 0.5, -0.7]), 6.0

    def rhs(t, y):
        return np.concatenate([y[3:], fpu_acceleration(y[:3])])

    sol = solve_ivp(rhs, (0.0, T), np.concatenate([x0, v0]), method="DOP853", rtol=3e-14, atol=1e-15)
    return x0, v0, T, sol.y[:3, -1]


NONLINEAR_STEPS = {
    "verlet": [0.2, 0.1, 0.05, 0.025],
    "verlet-kahan": [0.2, 0.1, 0.05, 0.025],
    "verlet-kahan": [0.2, 0.1, 0.05, 0.025],
    "yoshida4": [0.2, 0.15, 0.1, 0.075, 0.05],
    "blanes-moan4": [0.3, 0.2, 0.15, 0.1, 0.075],
    "blanes-moan6": [0.3, 0.2, 0.15, 0.1, 0.075],
    "kahan-li8": [0.3, 0.2, 0.15, 0.1, 0.075],
    "rk4": [0.2, 0.15, 0.1, 0.075, 0.05],
    "newmark": [0.2, 0.1, 0.05, 0.025],
    "newmark-linear": [0.2, 0.1, 0.05, 0.025],
    "hht": [0.2, 0.1, 0.05, 0.025],
}


@pytest.mark.parametrize("name", FINITE_ORDER)
def test_observed_order_on_a_nonlinear_chain(name, fpu_reference):
    """Nonlinear forces exercise every order condition of the coefficient tables."""
    x0, v0, T, ref = fpu_reference
    hs, errs = [], []
    for target in NONLINEAR_STEPS[name]:
        h, n = step_grid(T, target)
        tr = integrate(INTEGRATORS[name](), Problem(fpu_acceleration), x0, v0, h, n, record_every=n)
        hs.append(h)
        errs.append(np.max(np.abs(tr.x[-1, :, 0] - ref)))
    assert min(errs) > 1e-11
    assert abs(slope(hs, errs) - INTEGRATORS[name].order) < 0.25, errs


@pytest.mark.parametrize("name, h, factor", [("blanes-moan4", 0.4, 100.0), ("blanes-moan6", 0.55, 1000.0)])
def test_blanes_moan_beats_yoshida_at_equal_cost(name, h, factor, problem, exact, reference):
    """Same force evaluations per unit time: Yoshida's step is 3/stages of Blanes–Moan's."""
    T = 10.0
    xe, _ = exact.at(T)

    def err(method, target):
        hh, n = step_grid(T, target)
        tr = integrate(INTEGRATORS[method](), problem, reference["x0"], reference["v0"], hh, n, record_every=n)
        return np.max(np.abs(tr.x[-1, :, 0] - xe))

    h_yoshida = h * 3.0 / INTEGRATORS[name].evals_per_step
    assert err(name, h) * factor < err("yoshida4", h_yoshida)


# --- energy over 3·10⁴ steps -----------------------------------------------------------------------

#: Steps with a visible but small energy error on the seed (ω_max = 1.29).
ENERGY_STEPS = {"verlet": 0.1, "verlet-kahan": 0.1, "yoshida4": 0.3, "blanes-moan4": 0.6, "blanes-moan6": 0.9,
                "kahan-li8": 0.9, "rk4": 0.1}


@pytest.fixture(scope="module")
def cheap_seed(seed_system):
    """The seed chain with its acceleration as one 3×3 product (cheap for 10⁵ steps), its energy,
    and a batch of 4 initial states with zero total momentum."""
    A = seed_system.acceleration(np.eye(3))
    K = -seed_system.masses[:, None] * A
    m = seed_system.masses

    def energy(x, v):  # x, v (..., N, B) -> (..., B)
        return 0.5 * np.einsum("i,...ib->...b", m, v * v) + 0.5 * np.einsum("...ib,ij,...jb->...b", x, K, x)

    rng = np.random.default_rng(7)
    X0, V0 = rng.standard_normal((3, 4)), rng.standard_normal((3, 4))
    # no centre-of-mass drift: over 10⁵ steps it would make x ~ 10⁴ and xᵀKx lose ~1e-7 to cancellation
    V0 -= (m @ V0) / m.sum()
    return Problem(lambda x: A @ x), energy, X0, V0


#: The implicit Newmark/HHT steps are not symplectic but conserve (average acceleration) or bound or
#: dissipate the energy of a linear chain; tests/run/test_newmark.py checks those properties instead.
EXPLICIT_FINITE = [n for n in FINITE_ORDER if not isinstance(registry.method(n), ImplicitStep)]


@pytest.mark.parametrize("name", EXPLICIT_FINITE)
def test_energy_error_over_3e4_steps(name, cheap_seed):
    """Symplectic: the error after 3·10⁴ steps is no larger than in the first 300 (≥ 5 periods of the
    slowest mode). RK4: it keeps growing (100 times the steps, more than 50 times the error)."""
    problem, energy, X0, V0 = cheap_seed
    steps, every = 30_000, 10
    tr = integrate(INTEGRATORS[name](), problem, X0, V0, ENERGY_STEPS[name], steps, record_every=every)
    e = energy(tr.x, tr.v)
    err = np.abs(e - e[0]) / np.abs(e[0])
    early = err[: 300 // every + 1].max(axis=0)
    late = err.max(axis=0)
    assert np.all(early > 1e-12)  # an error to watch, well above roundoff
    if INTEGRATORS[name].symplectic:
        assert np.all(late < 1.5 * early + 1e-12), (late, early)
    else:
        assert np.all(late > 50.0 * early), (late, early)


# --- batches -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(INTEGRATORS))
def test_batch_equals_one_run_per_column(name, problem):
    rng = np.random.default_rng(3)
    X0, V0 = rng.standard_normal((3, 3)), rng.standard_normal((3, 3))
    batch = integrate(INTEGRATORS[name](), problem, X0, V0, 0.07, 150, record_every=10)
    for j in range(3):
        one = integrate(INTEGRATORS[name](), problem, X0[:, j], V0[:, j], 0.07, 150, record_every=10)
        assert np.allclose(batch.x[..., j], one.x[..., 0], rtol=0, atol=1e-13)
        assert np.allclose(batch.v[..., j], one.v[..., 0], rtol=0, atol=1e-13)
    assert batch.force_evals == one.force_evals


def test_step_api_equals_the_driver(problem, reference):
    for name in ("verlet", "blanes-moan6", "rk4", "expm"):
        integ = INTEGRATORS[name]()
        tr = integrate(integ, problem, reference["x0"], reference["v0"], 0.1, 20)
        state = integ.init(problem, reference["x0"][:, None], reference["v0"][:, None])
        for _ in range(20):
            state = integ.step(problem, state, 0.1)
        assert state.i == 20
        assert np.allclose(state.x, tr.x[-1], rtol=0, atol=1e-15)
        assert np.allclose(state.v, tr.v[-1], rtol=0, atol=1e-15)


# --- every method against the exact solution on the reference scene ------------------------------

#: Largest position error over t ∈ [0, 100] at dt = 0.1 (measured ×~2–3; Verlet ≈ ω³h²t/24 = 0.09 at the end).
SCENE_TOLERANCE = {"verlet": 0.15, "verlet-kahan": 0.15, "yoshida4": 6e-3, "blanes-moan4": 2e-6, "blanes-moan6": 2e-10,
                   "kahan-li8": 5e-11, "rk4": 1e-3, "expm": 1e-12, "chebyshev": 1e-12,
                   "newmark": 0.3, "newmark-linear": 0.15, "hht": 0.3}


@pytest.mark.parametrize("name", list(INTEGRATORS))
def test_every_fixed_step_method_agrees_with_exact_on_the_scene(name, problem, exact, reference):
    tr = integrate(INTEGRATORS[name](), problem, reference["x0"], reference["v0"], reference["dt"],
                   reference["steps"])
    xe, _ = exact.at(tr.t)
    assert np.max(np.abs(tr.x[..., 0] - xe)) < SCENE_TOLERANCE[name]
    assert tr.force_evals == INTEGRATORS[name]().force_evals(problem, reference["dt"], reference["steps"])


@pytest.mark.parametrize("name, tol, bound", [("rk45", 1e-8, 5e-6), ("dop853", 1e-10, 2e-8),
                                               ("lsoda", 1e-10, 2e-7)])
def test_adaptive_methods_agree_with_exact_on_the_scene(name, tol, bound, problem, exact, reference):
    t = np.arange(reference["steps"] + 1) * reference["dt"]
    res = ADAPTIVE[name]().solve(problem, reference["x0"], reference["v0"], t, rtol=tol, atol=tol)
    xe, ve = exact.at(t)
    assert res.x.shape == (t.size, 3, 1)
    assert np.max(np.abs(res.x[..., 0] - xe)) < bound
    assert np.max(np.abs(res.v[..., 0] - ve)) < bound
    assert res.force_evals > 100


def test_adaptive_method_flattens_a_batch(seed_system, problem):
    rng = np.random.default_rng(5)
    X0, V0 = rng.standard_normal((3, 4)), rng.standard_normal((3, 4))
    t = np.linspace(0.0, 20.0, 41)
    res = ADAPTIVE["dop853"]().solve(problem, X0, V0, t, rtol=1e-10, atol=1e-10)
    spec = spectrum(seed_system.masses, seed_system.spring_ends, seed_system.stiffness)
    xe, ve = ModalSolution.from_initial(spec, X0, V0).at(t)
    assert res.x.shape == (41, 3, 4)
    assert np.max(np.abs(res.x - xe)) < 1e-7 and np.max(np.abs(res.v - ve)) < 1e-7


def test_adaptive_method_refuses_bad_tolerances(problem, reference):
    with pytest.raises(RunRefused, match="rtol"):
        ADAPTIVE["rk45"]().solve(problem, reference["x0"], reference["v0"], [0.0, 1.0], rtol=0.0, atol=1e-9)


# --- propagators ---------------------------------------------------------------------------------

@pytest.mark.parametrize("which", ["seed", "walled"])
def test_expm_step_is_the_matrix_exponential(which, seed_system, problem):
    if which == "seed":
        chain, A = problem.linear, seed_system.acceleration(np.eye(3))
    else:
        chain, A = random_chain(7, seed=11)
    n, h = chain.n, 0.37
    first_order = np.block([[np.zeros((n, n)), np.eye(n)], [A, np.zeros((n, n))]])
    phi = step_matrix(Problem(lambda x: A @ x, linear=chain), h)
    assert np.max(np.abs(phi - scipy.linalg.expm(h * first_order))) < 1e-13


def test_chebyshev_takes_long_steps_on_a_random_chain():
    chain, A = random_chain(12, seed=2)
    problem = Problem(lambda x: A @ x, linear=chain)
    rng = np.random.default_rng(4)
    X0, V0 = rng.standard_normal((12, 2)), rng.standard_normal((12, 2))
    h, steps = 5.0, 20  # h·ω_max ≈ 12: far beyond any step method's stability limit
    tr = integrate(ChebyshevPropagator(), problem, X0, V0, h, steps, record_every=5)
    xe, ve = ModalSolution.from_initial(chain.spectrum(), X0, V0).at(tr.t)
    assert np.max(np.abs(tr.x - xe)) < 1e-11 and np.max(np.abs(tr.v - ve)) < 1e-11
    degree = ChebyshevCoefficients.from_bessel(h, chain.omega2_bound()).degree
    assert tr.force_evals == 2 * degree * steps


def test_chebyshev_runs_from_a_stencil():
    """A uniform walled chain, acceleration by slicing (no matrix anywhere), against the exact solution."""
    n = 300

    def stencil(x):
        pad = np.zeros((1,) + x.shape[1:])
        xp = np.concatenate([pad, x, pad])
        return xp[:-2] - 2.0 * x + xp[2:]

    chain = LinearChain(np.ones(n), np.array([(-1, 0), *[(j, j + 1) for j in range(n - 1)], (n - 1, -1)]),
                        np.ones(n + 1))
    j = np.arange(n)
    x0 = np.exp(-(((j - n / 2) / 10.0) ** 2))[:, None]
    v0 = np.zeros_like(x0)
    tr = integrate(ChebyshevPropagator(), Problem(stencil, linear=chain), x0, v0, 3.0, 10, record_every=10)
    xe, _ = ModalSolution.from_initial(chain.spectrum(), x0, v0).at(tr.t[-1])
    assert np.max(np.abs(tr.x[-1] - xe)) < 1e-12


@pytest.mark.parametrize("name", PROPAGATORS)
def test_propagators_refuse_a_problem_without_springs(name, seed_system):
    with pytest.raises(RunRefused, match=f"method '{name}' needs a linear chain of springs only"):
        integrate(INTEGRATORS[name](), Problem(seed_system.acceleration_fn), np.zeros(3), np.zeros(3), 0.1, 2)


@pytest.mark.parametrize("name", [n for n in INTEGRATORS if n != "rk4"])
def test_methods_without_damping_refuse_dampers(name, problem):
    damped = Problem(problem.acceleration, damping=lambda v: -0.1 * v, linear=problem.linear)
    with pytest.raises(RunRefused, match=name):
        integrate(INTEGRATORS[name](), damped, np.zeros(3), np.zeros(3), 0.1, 2)


# --- forcing and damping -------------------------------------------------------------------------

def forced_reference(c, T=8.0):
    """x'' = -x - c x' + cos(2t) from x = 0.3, v = 0 by a tight DOP853 (one mass on a wall spring)."""
    sol = solve_ivp(lambda t, y: [y[1], -y[0] - c * y[1] + math.cos(2 * t)], (0.0, T), [0.3, 0.0],
                    method="DOP853", rtol=3e-14, atol=1e-15)
    return sol.y[0, -1]


@pytest.mark.parametrize("name, c", [("verlet", 0.0), ("blanes-moan4", 0.0), ("kahan-li8", 0.0),
                                     ("rk4", 0.0), ("rk4", 0.4)])
def test_external_force_keeps_the_order(name, c):
    """Kicks see a_ext at their own stage times; RK4 also takes damping."""
    T = 8.0
    ref = forced_reference(c, T)
    problem = Problem(lambda x: -x, damping=(lambda v: -c * v) if c else None,
                      external=lambda t: np.array([math.cos(2 * t)]))
    hs, errs = [], []
    for target in ([0.5, 0.4, 0.3, 0.2] if INTEGRATORS[name].order == 8 else [0.2, 0.1, 0.05, 0.025]):
        h, n = step_grid(T, target)
        tr = integrate(INTEGRATORS[name](), problem, [0.3], [0.0], h, n, record_every=n)
        hs.append(h)
        errs.append(abs(tr.x[-1, 0, 0] - ref))
    assert min(errs) > 1e-12
    assert abs(slope(hs, errs) - INTEGRATORS[name].order) < 0.3, errs
