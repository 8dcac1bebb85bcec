"""plan and bench on scenes without a closed-form error model (issue 11, item 6): damped +
forced (`building`), gravity (`hanging`), and a uniform [chain] above 2000 masses.

Contract: every reachable step candidate, run with its planned dt, meets TOL against the exact
solution (the augmented matrix exponential, cross-checked against DOP853 here; the chain's
closed-form modal solution computed in the test).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import helpers
import springchain as sc
from springchain.cli import main
from springchain.derive.scene import load_scene
from springchain.numeric.exact.linear import AugmentedLinear
from springchain.numeric.run.simulate import run_methods

ROOT = Path(__file__).resolve().parents[2]
#: Largest force evaluations of one contract run (costlier candidates are skipped: not a timing test).
EVAL_BUDGET = 60_000

LONG_CHAIN = """
name = "longchain"
[parameters]
m = 1.0
k = 1.0
[chain]
n = 2500
mass = "m"
k = "k"
left = "wall"
right = "free"
[initial]
x = "0.01*sin(3*pi*(i + 1)/(n + 1)) + 0.001*sin(40*pi*(i + 1)/(n + 1))"
v = "0"
[simulation]
dt = 0.1
steps = 100
"""


def system_at_defaults(scene):
    return helpers.system_of(scene)[1]


def dense_exact(system, x0, v0, t):
    x, _ = AugmentedLinear.from_system(system).solve(x0, v0, t, float(t[1] - t[0]))
    return x


def chain_exact(x0, t, n):
    """Wall-free uniform chain (m = k = 1), v0 = 0: ω_j = 2 sin((2j−1)π/(2(2n+1))), shapes sin(...)."""
    j = np.arange(1, n + 1)
    i = np.arange(n)
    S = np.sin(np.outer(i + 1, 2 * j - 1) * np.pi / (2 * n + 1))
    S /= np.linalg.norm(S, axis=0)
    w = 2 * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))
    q0 = S.T @ x0
    return (S @ (q0[:, None] * np.cos(np.outer(w, t)))).T


def check_candidates(plan, system, x0, v0, exact):
    """Every reachable step candidate meets TOL when run (within the evaluation budget)."""
    checked = 0
    for c in plan.candidates:
        if c.steps is None or c.steps * max(c.method.traits.evals_per_step, 1) > EVAL_BUDGET:
            continue
        run = run_methods(system, x0, v0, c.dt, c.steps, [c.name])[c.name]
        err = float(np.max(np.abs(run.x - exact(run.t))))
        assert err <= plan.tol, (c.name, c.dt, err, plan.tol, c.model)
        checked += 1
    return checked


@pytest.mark.parametrize("name, tol, t_end", [("building", 1e-5, 8.0), ("hanging", 1e-8, 10.0)])
def test_plan_steps_meet_tol(name, tol, t_end):
    scene = load_scene(ROOT / "scenes" / f"{name}.toml")
    system = system_at_defaults(scene)
    x0 = scene.x0
    v0 = scene.v0
    plan = sc.plan(scene, tol, t_end=t_end)
    assert plan.recommended.reachable and plan.recommended.predicted_error <= tol
    assert any("pilot-calibrated" in c.model for c in plan.candidates)
    assert any(c.name == "modal" and "exact" in c.model for c in plan.candidates)
    assert check_candidates(plan, system, x0, v0, lambda t: dense_exact(system, x0, v0, t)) >= 3


def test_augmented_reference_agrees_with_dop853():
    """The reference the planner measures against, checked independently."""
    scene = load_scene(ROOT / "scenes" / "building.toml")
    system = system_at_defaults(scene)
    t = np.linspace(0.0, 8.0, 1601)
    x = dense_exact(system, scene.x0, scene.v0, t)
    mod, p = system.module, system.params
    K, C, minv = mod.stiffness_matrix(**p), mod.damping_matrix(**p), 1 / system.masses

    def rhs(tt, z):
        f = -K @ z[:3] - C @ z[3:] + system.masses * mod.external_acceleration(tt, **p)
        return np.concatenate([z[3:], minv * f])

    sol = solve_ivp(rhs, (0, 8), np.zeros(6), method="DOP853", rtol=1e-12, atol=1e-16, t_eval=t)
    assert np.max(np.abs(sol.y[:3].T - x)) <= 1e-8 * np.max(np.abs(x))


def test_plan_long_uniform_chain_meets_tol():
    scene = load_scene("longchain.toml", text=LONG_CHAIN)
    system = system_at_defaults(scene)
    assert system.n > 2000
    tol = 1e-7
    plan = sc.plan(scene, tol, t_end=10.0)
    n = system.n
    checked = check_candidates(plan, system, scene.x0, scene.v0, lambda t: chain_exact(scene.x0, t, n))
    assert checked >= 3


@pytest.mark.parametrize("name", ["building", "hanging", "longchain"])
def test_quick_bench_runs_against_the_exact_solution(name, tmp_path, capsys):
    if name == "longchain":
        path = tmp_path / "longchain.toml"
        path.write_text(LONG_CHAIN)
    else:
        path = ROOT / "scenes" / f"{name}.toml"
    status = main(["bench", str(path), "--quick", "--json", "--no-progress", "--t-end", "5",
                   "--out", str(tmp_path / "out")])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["reference"].startswith("exact:")
    methods = {r["method"] for r in data["records"]}
    assert {"verlet", "dop853"} <= methods
    for r in data["records"]:
        assert np.isfinite(r["error"]) and r["error"] > 0
        if r["predicted_error"] is not None and r["error"] > 1e-12:
            # the pilot law is conservative: measured never far above predicted
            assert r["error"] <= 3 * r["predicted_error"], r
    assert (tmp_path / "out" / f"bench-{data['scene']}.md").exists()


def test_plan_refuses_scenes_without_an_exact_reference(tmp_path, capsys):
    text = (ROOT / "scenes" / "duffing.toml").read_text()
    text = text.replace("[initial]", '[damping]\nrayleigh = [0.01, 0.0]\n\n[initial]')
    path = tmp_path / "duffing_damped.toml"
    path.write_text(text)
    assert main(["plan", str(path), "--tol", "1e-6"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "exact solution" in err and "cubic springs" in err
    long_nonuniform = LONG_CHAIN.replace('mass = "m"', 'mass = "m*(1 + i % 2)"')
    path = tmp_path / "ln.toml"
    path.write_text(long_nonuniform)
    assert main(["plan", str(path), "--tol", "1e-6"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "uniform" in err
