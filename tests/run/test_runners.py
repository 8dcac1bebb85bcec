"""One method protocol (numeric.run), one registry, two recorders: the same frames whether kept or
streamed, and a new integrator that touches only the registry runs through simulate, plan and bench."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import springchain
from springchain.numeric.errors import RunRefused
from springchain.numeric.integrators.base import Integrator, Problem, StepKernel
from springchain.numeric.run import registry
from springchain.numeric.run.adaptive import AdaptiveRun
from springchain.numeric.run.exact import ExactSolution
from springchain.numeric.run.grid import Grid
from springchain.numeric.run.protocol import Kind, Options
from springchain.numeric.run.recorder import MemoryRecorder
from springchain.numeric.run.step import StepMethod


def test_every_name_has_one_method_of_the_right_kind():
    kinds = {name: type(registry.method(name)) for name in registry.names()}
    assert kinds["modal"] is ExactSolution and kinds["verlet"] is StepMethod and kinds["dop853"] is AdaptiveRun
    assert [registry.method(n).kind for n in registry.names()] == [registry.entry(n).kind for n in registry.names()]
    assert registry.names()[0] == registry.EXACT and springchain.method_names() == list(registry.names())
    with pytest.raises(RunRefused, match="unknown"):
        registry.method("euler")


def test_listing_the_names_imports_no_integrator():
    code = ("import sys\nfrom springchain.numeric.run import registry\nnames = registry.names()\n"
            "print(len(names), any(m.startswith('springchain.numeric.integrators') for m in sys.modules), "
            "'numpy' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd="/")
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == [str(len(registry.names())), "False", "False"]


def test_grid_records_every_kth_step_and_the_last():
    g = Grid(0.1, 10, 4)
    assert g.indices.tolist() == [0, 4, 8, 10] and g.frames == 4
    np.testing.assert_allclose(g.t, [0.0, 0.4, 0.8, 1.0], rtol=0, atol=1e-15)
    c = Grid.covering(100.0, 0.1)
    assert (c.steps, c.frames) == (1000, 1001) and c.t[-1] == 1000 * c.h


@pytest.mark.parametrize("name", ["modal", "verlet", "rk4", "dop853"])
def test_each_kind_runs_into_a_memory_recorder(seed_system, name):
    grid = Grid(0.05, 40, 8)
    x0, v0 = np.array([0.1, 0.0, -0.05]), np.zeros(3)
    rec = MemoryRecorder(grid.frames, seed_system.n)
    registry.method(name, Options(rtol=1e-12, atol=1e-14)).run(seed_system, x0, v0, grid, rec)
    exact = MemoryRecorder(grid.frames, seed_system.n)
    registry.method("modal").run(seed_system, x0, v0, grid, exact)
    tol = {"modal": 1e-15, "verlet": 1e-3, "rk4": 1e-6, "dop853": 1e-10}[name]
    assert np.max(np.abs(rec.x - exact.x)) <= tol and np.max(np.abs(rec.v - exact.v)) <= 10 * tol


def test_streamed_and_kept_frames_agree_on_a_chain(tmp_path):
    """A short [chain] run streamed to the NPZ (API) equals the same run kept in memory."""
    from springchain._modules import load_module
    from springchain.numeric.run.simulate import run_methods
    from springchain.numeric.system import System

    text = Path(springchain.load("chain100k").file).read_text(encoding="utf-8")
    text = "\n".join("n = 64" if l.startswith("n =") else 'name = "c64"' if l.startswith("name =") else l
                     for l in text.splitlines())
    scene_file = tmp_path / "c64.toml"
    scene_file.write_text(text + "\n")
    scene = springchain.load(scene_file)
    streamed = springchain.simulate(scene, methods=["modal", "verlet"], steps=50, record_every=10,
                                    out=tmp_path / "out")
    system = System.from_module(load_module(scene)[0])
    kept = run_methods(system, scene.x0, scene.v0, scene.dt, 50, ["modal", "verlet"], 10)
    for name in ("modal", "verlet"):
        np.testing.assert_allclose(streamed.x[name], kept[name].x, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(streamed.v[name], kept[name].v, rtol=1e-12, atol=1e-13)


# -- a new integrator touches only the registry -------------------------------------------------------
class SymplecticEuler(Integrator):
    """``v ← v + h a(x);  x ← x + h v`` (first order, symplectic): a method the project does not ship."""

    name = "symplectic-euler"
    order = 1
    symplectic = True
    evals_per_step = 1.0
    stability_limit = 2.0

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        acc = problem.acceleration

        def step(x, v, a, i):
            v = v + h * a
            x = x + h * v
            return x, v, acc(x)
        return step


@pytest.fixture
def euler():
    with registry.registered(SymplecticEuler.name, Kind.STEP, SymplecticEuler):
        yield SymplecticEuler.name


def test_a_registered_integrator_runs_through_simulate(euler, seed_path):
    run = springchain.simulate(seed_path, methods=["modal", euler], steps=400, progress=False)
    err = np.max(np.abs(run.x[euler] - run.x["modal"]))
    assert 1e-4 < err < 0.5, err  # first order: a visible but bounded error at dt = 0.1
    assert euler in springchain.method_names()
    # first order: halving dt halves the error (a slope fit against the exact run)
    errs = [np.max(np.abs((r := springchain.simulate(seed_path, methods=["modal", euler], dt=dt,
                                                     steps=round(20 / dt), progress=False)).x[euler]
                          - r.x["modal"])) for dt in (0.02, 0.01, 0.005)]
    slope = np.polyfit(np.log([0.02, 0.01, 0.005]), np.log(errs), 1)[0]
    assert abs(slope - 1.0) < 0.15, (errs, slope)


def test_a_registered_integrator_is_planned_and_benched(euler):
    plan = springchain.plan("seed", tol=1e-3)
    mine = [c for c in (*plan.candidates, *plan.unreachable) if c.name == euler]
    assert len(mine) == 1 and mine[0].dt is not None and mine[0].predicted_error <= 1e-3
    result = springchain.bench("seed", quick=True, methods=[euler])
    assert result.records and {r.method for r in result.records} == {euler}
    for r in result.records:  # measured against the extended-precision reference, predicted by its model
        assert 0 < r.error and r.predicted_error is not None and r.error / 3 <= r.predicted_error <= 3 * r.error


def test_unregistered_again_after_the_block(euler):
    assert euler in registry.names()
    registry.unregister(euler)
    try:
        assert euler not in registry.names()
        with pytest.raises(RunRefused, match="unknown"):
            registry.method(euler)
    finally:
        registry.register(euler, Kind.STEP, SymplecticEuler)


def test_traits_are_declared_by_the_implementations():
    t = registry.method("kahan-li8").traits
    assert (t.order, t.symplectic, t.stability_limit) == (8, True, registry.implementation("kahan-li8").stability_limit)
    assert math.isinf(registry.method("modal").traits.order) and registry.method("modal").traits.evals_per_step == 0
    assert math.isnan(registry.method("dop853").traits.evals_per_step)
