"""Newmark-β and HHT-α (issue 20, item 3): the textbook properties of the schemes, measured on the
kernels themselves (one step from unit states gives the method's one-step matrix), and order 2
against exact solutions and against DOP853 references built in the test from the scene's TOML."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import springchain as sc
from springchain.numeric.run.driver import integrate
from springchain.numeric.integrators.base import LinearChain, Problem
from springchain.numeric.integrators.newmark import HHTAlpha, NewmarkAverage, NewmarkLinear, NewmarkParameters
from springchain.numeric.run import registry
from springchain.numeric.run.implicit import ImplicitStep
from springchain.numeric.run.protocol import Kind


def _sdof(omega: float):
    """q'' = -omega^2 q as a one-mass chain on a wall spring (unit mass)."""
    chain = LinearChain(np.array([1.0]), np.array([[0, -1]]), np.array([omega**2]))
    return Problem(lambda x: -omega**2 * x, linear=chain)


def _measured_map(integ, omega: float, h: float) -> np.ndarray:
    """The (x, h v, h^2 a) one-step matrix of the kernel, from one step on each unit state."""
    prob = _sdof(omega)
    kern = integ.kernel(prob, h)
    cols = []
    for x, v, a in ((1.0, 0.0, 0.0), (0.0, 1.0 / h, 0.0), (0.0, 0.0, 1.0 / h**2)):
        X, V = np.array([[x]]), np.array([[v]])
        A = np.array([[a]])
        if integ.parameters.alpha != 0.0:
            A = np.vstack([A, -omega**2 * X])  # the force of the step below: g(x) + D v
        x1, v1, a1 = kern(X, V, A, 0)
        cols.append([x1[0, 0], h * v1[0, 0], h * h * a1[0, 0]])
    return np.array(cols).T


def _principal(M):
    lam = np.linalg.eigvals(M)
    lam = lam[np.argsort(-np.abs(lam.imag))][0]
    return abs(lam), abs(np.angle(lam))


@pytest.mark.parametrize("cls, beta, theta", [
    (NewmarkAverage, 0.25, lambda z: 2 * np.arctan(z / 2)),
    (NewmarkLinear, 1 / 6, lambda z: 2 * np.arctan(z / 2 / np.sqrt(1 - z * z / 12))),
])
@pytest.mark.parametrize("z", [0.05, 0.3, 1.0, 2.5])
def test_period_elongation_formula(cls, beta, theta, z):
    """gamma = 1/2: no amplitude error (rho = 1), phase per step theta(z): T_num/T = z/theta."""
    rho, th = _principal(_measured_map(cls(), 2.0, z / 2.0))
    assert rho == pytest.approx(1.0, abs=1e-13)
    assert th == pytest.approx(theta(z), rel=1e-12)
    elongation = z / th - 1.0
    small = z * z / (12 if beta == 0.25 else 24)
    if z <= 0.3:
        assert elongation == pytest.approx(small, rel=0.02)


@pytest.mark.parametrize("alpha", [-0.05, -0.1, -1 / 3])
def test_hht_numerical_damping(alpha):
    integ = HHTAlpha(alpha=alpha)
    for z in (0.02, 0.1, 0.5, 2.0, 10.0):
        M = _measured_map(integ, 3.0, z / 3.0)
        rho, th = _principal(M)
        ref_rho, ref_th = _principal(integ.parameters.amplification(z))
        assert rho == pytest.approx(ref_rho, rel=1e-12) and th == pytest.approx(ref_th, rel=1e-10)
        assert rho < 1.0
        xi = -math.log(rho) / th
        if z <= 0.1:  # the leading term of HHT's algorithmic damping ratio
            assert xi == pytest.approx(-alpha * (1 + alpha) ** 2 * z**3 / 8, rel=0.02)
    # the spectral radius at infinity: (1 + alpha)/(1 - alpha)
    rho_inf = max(abs(np.linalg.eigvals(integ.parameters.amplification(1e7))))
    assert rho_inf == pytest.approx((1 + alpha) / (1 - alpha), rel=1e-4)  # (a triple root at alpha = -1/3)


def test_average_acceleration_unconditionally_stable():
    """omega h = 100 for 10^4 steps: the energy of the trapezoidal rule stays exactly constant."""
    omega, h = 50.0, 2.0
    tr = integrate(NewmarkAverage(), _sdof(omega), np.array([1.0]), np.array([0.0]), h, 10_000, record_every=100)
    e = 0.5 * tr.v[..., 0] ** 2 + 0.5 * omega**2 * tr.x[..., 0] ** 2
    assert np.max(np.abs(e / e[0] - 1)) <= 1e-12
    hht = integrate(HHTAlpha(), _sdof(omega), np.array([1.0]), np.array([0.0]), h, 200)
    assert abs(hht.x[-1, 0, 0]) < 1.0  # damped, never growing
    lin = NewmarkLinear()
    assert lin.stability_limit == pytest.approx(2 * math.sqrt(3), rel=1e-15)
    with pytest.raises(sc.RunRefused, match="stability limit"):
        sc.simulate("seed", methods=["newmark-linear"], dt=2 * math.sqrt(3) / math.sqrt(5 / 3) * 1.001, steps=3)


def test_parameter_table_checks_itself():
    with pytest.raises(ValueError, match="gamma"):
        NewmarkParameters(0.25, 0.4)
    with pytest.raises(ValueError, match="HHT"):
        NewmarkParameters(0.25, 0.55, -0.05)
    with pytest.raises(sc.RunRefused, match="alpha"):
        HHTAlpha(alpha=-0.5)
    assert NewmarkParameters.hht(-0.05).order == 2 and NewmarkParameters(0.25, 0.6).order == 1
    assert {"newmark", "newmark-linear", "hht"} <= set(registry.names(Kind.STEP)) <= set(sc.method_names())


def test_registered_through_the_run_layer():
    """Registry entries run by ImplicitStep (built on the system); traits declared by the classes."""
    for name, cls in (("newmark", NewmarkAverage), ("newmark-linear", NewmarkLinear), ("hht", HHTAlpha)):
        m = registry.method(name)
        assert isinstance(m, ImplicitStep) and m.kind is Kind.STEP and m.implementation is cls
        assert m.traits.order == 2 and m.traits.supports_damping and not m.traits.symplectic
    assert math.isinf(registry.method("newmark").traits.stability_limit)
    assert registry.method("newmark-linear").traits.stability_limit == pytest.approx(2 * math.sqrt(3), rel=1e-15)
    assert registry.method("hht").traits.evals_per_step == 2.0


def _slope(errors, steps):
    return float(np.polyfit(np.log(1.0 / np.asarray(steps)), np.log(errors), 1)[0])


@pytest.mark.parametrize("name", ["newmark", "newmark-linear", "hht"])
def test_order_two_damped_forced_ground(name):
    """Against the exact solution of damped + forced (building) and ground-shaken (building_quake) scenes."""
    for scene, dts, steps in (("building", (0.02, 0.01, 0.005), 0.4), ("building_quake", (0.01, 0.005, 0.0025), 0.4)):
        errs = []
        for dt in dts:
            n = int(round(steps / dt))
            run = sc.simulate(scene, methods=["modal", name], dt=dt, steps=n, progress=False)
            errs.append(run.summary["methods"][name]["max_position_difference"])
        assert _slope(errs, dts) == pytest.approx(-2.0, abs=0.15), (scene, errs)


def test_cubic_springs_newton_against_dop853(repo_root):
    """Duffing chain: Newton on the residual each step; order 2 against DOP853 built from the TOML."""
    data = tomllib.loads((repo_root / "scenes" / "duffing.toml").read_text())
    p = data["parameters"]
    names = list(data["masses"])
    m = np.array([p[data["masses"][k]] for k in names])
    springs = [(-1 if a == "wall" else names.index(a), -1 if b == "wall" else names.index(b), p[s["k"]], p[s["k3"]])
               for s in data["springs"] for a, b in [s["between"]]]
    x0, v0 = np.array(data["initial"]["x"], float), np.array(data["initial"]["v"], float)

    def rhs(t, y):
        x, v = y[:3], y[3:]
        f = np.zeros(3)
        for a, b, k, k3 in springs:
            d = (x[a] if a >= 0 else 0.0) - (x[b] if b >= 0 else 0.0)
            force = k * d + k3 * d**3
            if a >= 0:
                f[a] -= force
            if b >= 0:
                f[b] += force
        return np.concatenate([v, f / m])

    T = 5.0
    ref = solve_ivp(rhs, (0, T), np.concatenate([x0, v0]), method="DOP853", rtol=1e-13, atol=1e-15, dense_output=True)
    for name in ("newmark", "hht"):
        errs, dts = [], (0.02, 0.01, 0.005)
        for dt in dts:
            run = sc.simulate("duffing", methods=[name], dt=dt, steps=int(round(T / dt)), progress=False)
            errs.append(float(np.max(np.abs(run.x[name] - ref.sol(run.t)[:3].T))))
        assert _slope(errs, dts) == pytest.approx(-2.0, abs=0.15), (name, errs)


def test_chain_banded_solve(tmp_path):
    """A [chain] scene: sparse (banded) factorisation, never N x N; agrees with the exact solution at order 2."""
    from springchain._modules import system_of as _system
    from springchain.numeric.integrators.newmark import StructuralOperator

    path = tmp_path / "ch.toml"
    path.write_text('name = "ch"\n[parameters]\nm = 1.0\nk = 1.0\nc = 0.05\n[chain]\nn = 3000\nmass = "m"\nk = "k"\n'
                    'left = "wall"\nright = "free"\n[[dampers]]\nbetween = ["i", "wall"]\nc = "c"\n'
                    '[initial]\nx = "0.01*sin(pi*(i + 1)/(n + 1))"\n[simulation]\ndt = 0.1\nsteps = 20\n')
    system, _ = _system(sc.load(str(path)))
    op = StructuralOperator.from_system(system)
    assert op.sparse
    import scipy.sparse

    assert scipy.sparse.issparse(op.tangent()) and scipy.sparse.issparse(op.damping)
    errs = []
    for dt in (0.2, 0.1):
        run = sc.simulate(str(path), methods=["verlet", "newmark"], dt=dt, steps=int(round(2.0 / dt)),
                          out=tmp_path / f"o{dt}", progress=False)
        errs.append(float(np.max(np.abs(run.x["newmark"] - run.x["verlet"]))))
    assert errs[1] < errs[0] / 3


def test_energy_on_a_linear_chain(seed_system):
    """On the seed chain (given as a bare matrix problem: the tangent is probed): average
    acceleration conserves the energy to roundoff, linear acceleration keeps its error bounded, HHT
    only loses energy."""
    A = seed_system.acceleration(np.eye(3))
    K = -seed_system.masses[:, None] * A
    m = seed_system.masses
    x0, v0 = np.array([0.3, -0.2, 0.5]), np.array([0.1, 0.4, -0.5])
    v0 = v0 - (m @ v0) / m.sum()

    def energy(tr):
        x, v = tr.x[..., 0], tr.v[..., 0]
        return 0.5 * np.einsum("i,si->s", m, v * v) + 0.5 * np.einsum("si,ij,sj->s", x, K, x)

    prob = Problem(lambda x: A @ x)
    steps = 20_000
    e = energy(integrate(NewmarkAverage(), prob, x0, v0, 0.3, steps, record_every=10))
    assert np.max(np.abs(e / e[0] - 1)) <= 1e-12
    e = energy(integrate(NewmarkLinear(), prob, x0, v0, 0.3, steps, record_every=10))
    err = np.abs(e / e[0] - 1)
    assert err[:101].max() > 1e-6 and err.max() < 1.5 * err[:101].max()
    e = energy(integrate(HHTAlpha(), prob, x0, v0, 0.3, steps, record_every=10))
    assert np.all(np.diff(e[::100]) < 0) and e[-1] < e[0]


@pytest.mark.parametrize("name", ["newmark", "hht"])
def test_newton_force_evaluations_counted(name):
    """Cubic springs: the reported force evaluations are the calls the step made (Newton iterations
    included), counted here by wrapping the acceleration; linear springs: the declared count."""
    from springchain._modules import system_of as _system
    from springchain.numeric.run.implicit import ImplicitStep

    for scene, extra in (("duffing", True), ("seed", False)):
        system, _ = _system(sc.load(scene))
        calls = [0]
        acc = system.acceleration_fn

        def counting(x):
            calls[0] += 1
            return acc(x)

        method = registry.method(name)
        assert isinstance(method, ImplicitStep)
        integ = method.integrator(system)
        steps = 200
        tr = integrate(integ, Problem(counting), system.masses * 0 + 0.1, system.masses * 0, 0.01, steps)
        declared = 1 + int(integ.evals_per_step) * steps
        if extra:  # Newton: every call counted, at least one more per step than declared
            assert tr.force_evals == calls[0] and tr.force_evals >= declared + steps
        else:  # HHT's force at the new step is a tangent product on linear springs (counted, not a call)
            assert tr.force_evals == declared


def test_hht_alpha_setting(capsys):
    """alpha reaches the step (more negative: more numerical damping of the response), is checked
    against [-1/3, 0] in one line before any derivation, and is refused for methods without it."""
    drift, errs = {}, {}
    for alpha in (0.0, -0.05, -1 / 3):  # the undamped seed chain: HHT only loses energy, more as alpha falls
        run = sc.simulate("seed", methods=["modal", "hht"], dt=0.05, steps=2000, alpha=alpha, progress=False)
        drift[alpha] = run.summary["methods"]["hht"]["energy_drift_relative"]
        errs[alpha] = run.summary["methods"]["hht"]["max_position_difference"]
    assert drift[0.0] < 1e-12 and 1e-5 < drift[-0.05] < drift[-1 / 3] / 2
    newmark = sc.simulate("seed", methods=["modal", "newmark"], dt=0.05, steps=2000, progress=False)
    assert errs[0.0] == pytest.approx(newmark.summary["methods"]["newmark"]["max_position_difference"], rel=1e-9)
    with pytest.raises(sc.RunRefused, match=r"alpha -0.5: accepted: -1/3 <= alpha <= 0"):
        sc.simulate("seed", methods=["hht"], alpha=-0.5)
    with pytest.raises(sc.RunRefused, match=r"a setting of hht, not of newmark"):
        sc.simulate("seed", methods=["newmark"], alpha=-0.1)
    from helpers import one_line_error, run_cli

    one_line_error(*run_cli(["simulate", "seed", "--method", "hht", "--alpha", "0.2"], capsys), "--alpha",
                   "-1/3 <= alpha <= 0")
