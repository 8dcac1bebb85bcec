"""The accuracy planner (issue 4, item 3): closed-form error models and the plan contract on the seed scene.

Contract: running any fixed-step candidate with its planned dt meets TOL with a
measured error no smaller than TOL/100 (the exact propagators are exempt from
the lower bound). Errors are measured against the extended-precision modal
reference at every step. No timing assertions.
"""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stdout
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import springchain.generated.seed as seed_module
from springchain.numeric.bench.workprecision import ExtendedModalReference
from springchain.numeric.run.driver import integrate
from springchain.numeric.run.grid import step_grid
from springchain.numeric.plan.error_models import LinearChainModel, OscillatorResponse, PowerLaw
from springchain.numeric.run import registry
from springchain.numeric.run.protocol import Kind
from springchain.numeric.integrators.base import Problem
from springchain.numeric.integrators.verlet import VelocityVerlet
from springchain.numeric.plan.planner import Planner
from springchain.numeric.modes.spectrum import spectrum
from springchain.numeric.system import System

INTEGRATORS = registry.classes(Kind.STEP)

ROOT = Path(__file__).resolve().parents[2]
SEED = ROOT / "scenes" / "seed.toml"
X0 = np.array([0.8552, 1.5376, 0.8834])
V0 = np.array([-1.9255, 0.6991, -0.2460])
T_END = 100.0
#: Largest force evaluations of one contract run; costlier candidates are checked on a shorter horizon.
EVAL_BUDGET = 40_000


@pytest.fixture(scope="module")
def seed():
    system = System.from_module(seed_module)
    return system, Problem.from_system(system), ExtendedModalReference.from_system(system, X0, V0)


@pytest.fixture(scope="module")
def planner(seed):
    system, _, _ = seed
    return Planner.for_system(system, X0, V0, T_END, 0.1, adaptive=False)


def measured_error(problem, reference, integrator, t_end, dt):
    """Largest position error over every step of a run with the planned dt (h = T/ceil(T/dt))."""
    h, n = step_grid(t_end, dt)
    tr = integrate(integrator, problem, X0, V0, h, n)
    x_ref, _ = reference.at(tr.t)
    return float(np.max(np.abs(tr.x[..., 0] - x_ref)))


# -- JSON shape ---------------------------------------------------------------------------------------
def test_plan_json_shape():
    from springchain.cli import main

    buf = io.StringIO()
    with redirect_stdout(buf):
        rc = main(["plan", str(SEED), "--tol", "1e-6", "--json"])
    assert rc == 0
    data = json.loads(buf.getvalue())
    assert set(data) == {"recommended", "candidates"}
    fields = {"method", "dt", "predicted_error", "predicted_seconds"}
    assert set(data["recommended"]) == fields
    names = [c["method"] for c in data["candidates"]]
    assert len(names) == len(set(names)) and "modal" in names and "verlet" in names and "dop853" in names
    for c in data["candidates"]:
        assert set(c) == fields
        assert isinstance(c["method"], str)
        assert c["predicted_error"] <= 1e-6 and c["predicted_seconds"] > 0
        if c["method"] in INTEGRATORS:
            assert isinstance(c["dt"], float) and c["dt"] > 0
        else:
            assert c["dt"] is None
    rec = data["recommended"]
    assert rec in data["candidates"]
    assert rec["predicted_seconds"] == min(c["predicted_seconds"] for c in data["candidates"])


def test_plan_unreachable_tolerance_exits_2(capsys):
    from springchain.cli import main

    assert main(["plan", str(SEED), "--tol", "1e-17"]) == 2
    err = capsys.readouterr().err
    assert "no method reaches" in err and err.count("\n") == 1


# -- the contract ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-9])
def test_planned_steps_meet_tol_without_waste(seed, planner, tol):
    _, problem, reference = seed
    plan = planner.plan(tol)
    fixed = [c for c in plan.candidates + plan.unreachable if c.name in INTEGRATORS]
    assert {c.name for c in fixed} == set(INTEGRATORS), "every fixed-step method is planned at these tolerances"
    for cand in fixed:
        assert cand.reachable, f"{cand.name} unreachable at {tol:g}"
        method = cand.method
        integ = method.integrator_class()
        exact = not math.isfinite(method.traits.order)
        assert cand.dt * planner.model.omega_max < method.traits.stability_limit
        t_end, dt = T_END, cand.dt
        for shorter in (20.0, 5.0, 1.0):  # the same contract on a shorter horizon when too costly here
            if integ.force_evals(problem, dt, round(t_end / dt)) <= EVAL_BUDGET:
                break
            cand = replace(planner, t_end=shorter).plan_step(method, tol)
            t_end, dt = shorter, cand.dt
        err = measured_error(problem, reference, integ, t_end, dt)
        assert err <= tol, f"{cand.name} at dt={dt:.4g} over t={t_end:g}: error {err:.3g} > tol {tol:g}"
        if not exact:
            assert err >= tol / 100, f"{cand.name} at dt={dt:.4g}: error {err:.3g} wastefully below tol/100"


def test_recommendation_is_cheapest_and_stable(planner):
    plan = planner.plan(1e-4)
    assert plan.recommended.predicted_seconds == min(c.predicted_seconds for c in plan.candidates)
    loose = planner.plan(1.0)  # accuracy is no constraint: stability bounds the step
    for c in loose.candidates:
        if c.dt is not None and c.name in INTEGRATORS:
            assert c.dt * planner.model.omega_max < c.method.traits.stability_limit


def test_below_rounding_floor_is_unreachable(planner):
    with pytest.raises(ValueError, match="no method reaches"):
        planner.plan(1e-17)
    plan = planner.plan(1e-12)  # the exact methods reach it, Verlet's steps would drown in rounding
    assert "verlet" in {c.name for c in plan.unreachable}
    # the exact methods, or a high-order step method whose compiled loop is cheaper still (plan times
    # the path a run takes: on this 3-mass scene, the compiled loop from its threshold on)
    rec = plan.recommended
    assert rec.reachable and rec.predicted_error <= 1e-12
    assert rec.name in {"modal", "expm"} or rec.name in {"blanes-moan6", "kahan-li8", "yoshida4", "blanes-moan4"}


# -- error models -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["verlet", "blanes-moan4"])
@pytest.mark.parametrize("dt", [0.2, 0.1, 0.05])
def test_error_models_match_measured(seed, planner, name, dt):
    _, problem, reference = seed
    integ = INTEGRATORS[name]()
    resp = planner.responses[registry.method(name)]
    h, n = step_grid(T_END, dt)
    err = measured_error(problem, reference, integ, T_END, dt)
    exact = planner.model.error(resp, h, n)
    envelope = planner.model.envelope(resp, h, n)
    assert err / 1.01 <= exact <= err * 1.01  # closed-form numerical solution: exact up to roundoff
    assert err <= envelope <= 3 * err
    # the leading-term formula C ω^{p+1} h^p t per mode, weighted by the modal amplitudes and shapes
    lead = abs(resp.leading_constant) * (planner.model.omega * h) ** (resp.order + 1) * n
    textbook = float(np.max(np.abs(planner.model.shapes) @ (planner.model.amplitudes[:, 0] * lead)))
    assert err / 3 <= textbook <= 3 * err


def test_leading_constants_from_coefficients():
    """Derived from each method's own polynomial propagator: Verlet 1/24 (ω³h²t/24), RK4 −1/120."""
    assert OscillatorResponse.from_integrator(VelocityVerlet()).leading_constant == pytest.approx(1 / 24, rel=1e-12)
    assert OscillatorResponse.from_integrator(INTEGRATORS["rk4"]()).leading_constant == pytest.approx(-1 / 120,
                                                                                                      rel=1e-12)
    bm4 = OscillatorResponse.from_integrator(INTEGRATORS["blanes-moan4"]())
    y4 = OscillatorResponse.from_integrator(INTEGRATORS["yoshida4"]())
    assert abs(bm4.leading_constant) < abs(y4.leading_constant) / 100  # the point of the optimised method


def test_phase_defect_matches_acos_where_acos_is_accurate():
    resp = OscillatorResponse.from_integrator(VelocityVerlet())
    z = np.array([0.3, 0.8, 1.5, 1.9])
    theta = np.arccos(1 - z**2 / 2)  # cos θ = 1 − z²/2
    assert np.allclose(resp.angle_defect(z), theta - z, rtol=1e-10, atol=1e-15)
    assert np.isnan(resp.angle_defect(np.array([2.1]))[0])  # beyond ω h = 2: unstable


def test_declared_order_is_checked():
    class WrongOrder(VelocityVerlet):
        order = 4

    with pytest.raises(ValueError, match="declared order 4"):
        OscillatorResponse.from_integrator(WrongOrder())


def test_rk4_amplitude_decay():
    resp = OscillatorResponse.from_integrator(INTEGRATORS["rk4"]())
    z = np.array([0.05, 0.1])
    assert np.allclose(resp.log_amplitude(z), 0.5 * np.log1p(-(z**6) / 72 + z**8 / 576), rtol=1e-10)


def test_model_of_a_wall_chain_without_rigid_modes():
    masses, ends, k = np.array([1.0, 2.0]), np.array([[-1, 0], [0, 1], [1, -1]]), np.array([1.0, 3.0, 2.0])
    spec = spectrum(masses, ends, k)
    model = LinearChainModel.from_spectrum(spec, np.array([0.1, -0.2]), np.array([0.0, 0.3]))
    assert model.omega.shape == (2,) and np.all(model.omega > 0)
    resp = OscillatorResponse.from_integrator(VelocityVerlet())
    assert model.envelope(resp, 10.0, 5) == math.inf  # unstable step


def test_power_law_roundtrip():
    law = PowerLaw.through(1e-5, 3e-4, 1e-8, 3e-7, t_ref=10.0)
    assert law.alpha == pytest.approx(1.0)
    assert law(1e-6, 20.0) == pytest.approx(2 * 3e-5)
    assert law.solve(6e-5, 20.0) == pytest.approx(1e-6)
