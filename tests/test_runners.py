"""One method protocol, two recorders (numeric.runners): the same frames whether kept or streamed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import springchain
from springchain.numeric.errors import RunRefused
from springchain.numeric.methods import METHOD_NAMES
from springchain.numeric.runners import (AdaptiveRunner, ExactMethod, Grid, MemoryRecorder, RunContext,
                                         StepMethod, method)


def test_every_name_has_one_method_of_the_right_kind():
    kinds = {name: type(method(name)) for name in METHOD_NAMES}
    assert kinds["modal"] is ExactMethod and kinds["verlet"] is StepMethod and kinds["dop853"] is AdaptiveRunner
    with pytest.raises(RunRefused, match="unknown"):
        method("euler")


def test_grid_records_every_kth_step_and_the_last():
    g = Grid(0.1, 10, 4)
    assert g.indices.tolist() == [0, 4, 8, 10]
    np.testing.assert_allclose(g.t, [0.0, 0.4, 0.8, 1.0], rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", ["modal", "verlet", "rk4", "dop853"])
def test_each_kind_runs_into_a_memory_recorder(seed_system, name):
    grid = Grid(0.05, 40, 8)
    rec = MemoryRecorder(grid.indices.shape[0], seed_system.n)
    x0, v0 = np.array([0.1, 0.0, -0.05]), np.zeros(3)
    method(name).run(RunContext(seed_system, rtol=1e-12, atol=1e-14), x0, v0, grid, rec)
    exact = MemoryRecorder(grid.indices.shape[0], seed_system.n)
    method("modal").run(RunContext(seed_system), x0, v0, grid, exact)
    tol = {"modal": 1e-15, "verlet": 1e-3, "rk4": 1e-6, "dop853": 1e-10}[name]
    assert np.max(np.abs(rec.x - exact.x)) <= tol and np.max(np.abs(rec.v - exact.v)) <= 10 * tol


def test_streamed_and_kept_frames_agree_on_a_chain(tmp_path):
    """A short [chain] run streamed to the NPZ (API) equals the same run kept in memory."""
    from springchain._modules import load_module
    from springchain.numeric.simulate import run_methods
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
