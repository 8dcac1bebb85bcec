"""The scaling benchmark (numeric.bench.scaling) and the symbolic cost (derive.symbolic_cost): correctness only.

No timing is asserted. Checked here:

* the Verlet error model that picks the step meets its tolerance on a real
  chain (fused/NumPy Verlet against the exact transform solution), and is not
  wastefully pessimistic;
* the crossover horizon solves its own equation;
* a tiny run produces every table field, the Markdown, the figure and JSON;
* LagrangesMethod and derive.model give the same M and K (exact SymPy
  equality), and the [chain] template's interior equation equals
  LagrangesMethod's interior row — so the timing comparison compares equal work;
* one symbolic case runs in a fresh process and reports its work;
* ``springchain scaling`` writes its files.
"""

from __future__ import annotations

import importlib
import json
import math

import numpy as np
import pytest
import sympy as sp

from springchain import symbolic_cost
from springchain.derive.chain import ChainModel
from springchain.derive.chain_codegen import render_chain_module
from springchain.derive.scene import load_scene
from springchain.numeric.bench import scaling, scaling_report
from springchain.numeric.compiled import fast
from springchain.numeric.exact.chain import ChainModal


@pytest.fixture(scope="module")
def cases(import_source):
    uniform = importlib.import_module("springchain.generated.chain100k")
    text = symbolic_cost.chain_scene_text(50, mass=symbolic_cost.RANDOM_MASS, k=symbolic_cost.RANDOM_K,
                                          name="test_random")
    random = import_source(render_chain_module(ChainModel(load_scene("random.toml", text)), bundled=False),
                           "random")
    return scaling.ChainCase("uniform", uniform), scaling.ChainCase("random", random)


# -- error model and crossover -------------------------------------------------------------------
@pytest.mark.parametrize("tol", [1e-3, 1e-5])
def test_error_model_step_meets_tolerance(tol):
    """Verlet with the model's step errs by at most ~tol (relative to the amplitude), and not 100× less."""
    module = importlib.import_module("springchain.generated.chain100k")
    n, t_end = 12, 40.0
    omega_max = 2.0 * math.sqrt(1.0 / 1.0)  # uniform chain, m = k = 1: ω_max < 2√(k/m)
    h0 = scaling.verlet_step_for(t_end, tol, omega_max)
    steps = scaling.verlet_steps(t_end, tol, omega_max)
    h = t_end / steps
    assert h <= h0 * (1 + 1e-12)
    # excite the fastest mode (zig-zag) plus a slow one
    i = np.arange(n)
    x0 = 0.01 * ((-1.0) ** i) + 0.005 * np.cos(np.pi * (i + 0.5) / n)
    v0 = np.zeros(n)
    fv = fast.FusedVerlet.from_module(module, None, n, h, fast.Backend.NUMPY)
    x, v, a = x0.copy(), v0.copy(), fv.force(x0)
    fv.advance(x, v, a, steps)
    exact, _ = ChainModal.from_module(module, None, x0, v0).at(steps * h)
    err = np.max(np.abs(x - exact)) / np.max(np.abs(x0))
    assert err <= 2.0 * tol
    assert err >= tol / 100.0


def test_stability_cap():
    assert scaling.verlet_step_for(1e-6, 1.0 - 1e-9, 10.0) <= scaling.STABLE_OMEGA_H / 10.0
    assert scaling.verlet_steps(1.0, 1e-6, 0.0) == 1


@pytest.mark.parametrize("c_exact", [1e-4, 3.0, 5e3])
def test_crossover_solves_its_equation(c_exact):
    c_step, tol, w = 2e-6, 1e-6, 2.0
    t = scaling.crossover_time(c_exact, c_step, tol, w)
    h = scaling.verlet_step_for(t, tol, w)
    # continuous step count at T*: exact set-up == steps · per-step cost
    assert math.isclose(t / h * c_step, c_exact, rel_tol=1e-9)
    # beyond T* the exact solution is cheaper, before it Verlet is
    assert scaling.verlet_steps(2 * t, tol, w) * c_step > c_exact
    assert (0.5 * t) / scaling.verlet_step_for(0.5 * t, tol, w) * c_step < c_exact


def test_crossover_when_stability_limits_the_step():
    # a loose tolerance: the accuracy step is beyond 1.9/ω, so steps = T ω / 1.9
    c_exact, c_step, tol, w = 2e-3, 1e-3, 0.9, 1.0
    t = scaling.crossover_time(c_exact, c_step, tol, w)
    assert math.isclose(t * w / scaling.STABLE_OMEGA_H * c_step, c_exact, rel_tol=1e-12)


# -- a tiny run ----------------------------------------------------------------------------------------
def test_tiny_run_has_every_field_and_writes_outputs(cases, tmp_path):
    uniform, random = cases
    config = scaling.ScalingConfig(sizes=(3, 7), svd_max=7, dense_max=3, tridiagonal_max=7, budget=0.0,
                                   step_budget=0.0)
    lines = []
    result = scaling.run(uniform, random, config, progress=lines.append)
    assert [r["n"] for r in result.records] == [3, 7]
    assert any("N =" in line for line in lines)
    needed = ["setup_dense_svd", "setup_tridiagonal", "eval_dense", "setup_transform", "eval_transform",
              "step_numpy", "step_numpy_random", "floor", "floor_copy", "verlet_steps", "cost_verlet",
              "crossover_transform", "crossover_dense", "cheaper_uniform", "cheaper_random"]
    for rec in result.records:
        for key in needed:
            assert rec.get(key) is not None, key
            if isinstance(rec[key], float):
                assert rec[key] > 0
    assert result.records[0]["setup_dense_eigh"] is not None and result.records[1]["setup_dense_eigh"] is None
    if fast.available():
        assert result.records[-1]["step_fused"] > 0 and result.headline["fused_over_floor"] > 0
    head = result.headline
    assert head["n"] == 7 and set(head["ns_per_mass"]) >= {"step_numpy", "step_fused", "floor"}
    md = scaling_report.markdown(result)
    assert "| N |" in md and "floor" in md and "T*" in md
    paths = scaling_report.write(result, tmp_path)
    assert [p.name for p in paths] == ["scaling.json", "scaling.md", "scaling.png"]
    data = json.loads(paths[0].read_text())
    assert data["records"][0]["n"] == 3 and data["config"]["sizes"] == [3, 7]
    assert paths[2].stat().st_size > 1000


def test_config_refuses_nonsense():
    with pytest.raises(ValueError):
        scaling.ScalingConfig(sizes=(1,))
    with pytest.raises(ValueError):
        scaling.ScalingConfig(tol=2.0)


def test_interleaved_timing_and_floor_calls():
    calls = scaling.floor_calls(1000)
    assert "floor_copy" in calls and ("floor_stream" in calls) == fast.available()
    best = scaling.interleaved_seconds({**calls, "two": (lambda: None, 2)}, budget=0.0, min_rounds=2)
    assert set(best) == set(calls) | {"two"} and all(0 < v < 1 for v in best.values())
    assert 0.0 < scaling.best_seconds(lambda: None, budget=0.0) < 1e-3  # a call of a lambda: sub-millisecond


# -- symbolic cost: equal work ---------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 2, 3, 6])
def test_model_and_lagranges_method_give_the_same_matrices(n):
    M_lag, K_lag = symbolic_cost.lagrange_matrices(n)
    M_ours, K_ours = symbolic_cost.model_matrices(n)
    assert M_lag.shape == M_ours.shape == (n, n)
    assert (M_lag - M_ours).expand() == sp.zeros(n, n)
    assert (K_lag - K_ours).expand() == sp.zeros(n, n)
    if n > 1:
        assert K_ours != sp.zeros(n, n)


def test_chain_template_equals_lagranges_interior_row():
    n = 5
    lm, q, m, k = symbolic_cost.lagrange_system(n)
    model = ChainModel(load_scene("c.toml", symbolic_cost.chain_scene_text(n)))
    for i in range(1, n - 1):
        ours = model.interior_equation().subs(model.i, i).xreplace(
            {model.xm: q[i - 1], model.x0: q[i], model.xp: q[i + 1]})
        assert sp.expand(ours - lm.forcing[i]) == 0
        assert sp.expand(model.mass - lm.mass_matrix[i, i]) == 0


@pytest.mark.parametrize("route", list(symbolic_cost.Route), ids=lambda r: r.value)
def test_work_reports_its_phases(route):
    rec = symbolic_cost.work(route, 3)
    assert rec["total"] > 0
    if route is symbolic_cost.Route.ELEMENTS:
        assert math.isclose(rec["total"], rec["scene"] + rec["equations"] + rec["modes"] + rec["codegen"])
        assert rec["total_without_modes"] < rec["total"]


def test_one_case_in_a_fresh_process():
    rec = symbolic_cost.measure(symbolic_cost.Route.CHAIN, 3, timeout=120)
    assert rec["total"] > 0 and rec["wall"] > rec["total"] and rec["source_lines"] > 10


def test_ratios_and_markdown_from_records():
    recs = [{"route": "chain", "n": 40, "total": 0.1, "wall": 1.0, "wall_minus_baseline": 0.2},
            {"route": "elements", "n": 40, "total": 2.0, "total_without_modes": 1.0, "modes": 1.0, "wall": 3.0,
             "wall_minus_baseline": 2.2},
            {"route": "lagrange", "n": 40, "total": 5.0, "wall": 6.0, "wall_minus_baseline": 5.2}]
    ratios = symbolic_cost._ratios(recs)
    assert math.isclose(ratios["40"]["chain"], 50.0)
    assert math.isclose(ratios["40"]["elements"], 2.5) and math.isclose(ratios["40"]["elements_without_modes"], 5.0)
    md = symbolic_cost.markdown(symbolic_cost.SymbolicResult(0.8, recs, ratios))
    assert "| 40 | 0.1 | 2 | 1 | 1 | 5 | 50.0× | 2.5× | 5.0× |" in md


def test_cli_scaling_writes_its_files(tmp_path, capsys, monkeypatch):
    from springchain.cli import main

    quick = scaling.interleaved_samples
    monkeypatch.setattr(scaling, "interleaved_samples",
                        lambda calls, **kw: quick(calls, budget=0.0, min_rounds=1, min_time=0.0))

    assert main(["scaling", "--max-n", "5", "--symbolic-max-n", "0", "--out", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["symbolic"] is None and [r["n"] for r in out["scaling"]["records"]] == [3, 5]
    for name in ("scaling.json", "scaling.md", "scaling.png"):
        assert (tmp_path / name).exists()


def test_tiny_run_without_numba(cases, monkeypatch):
    """Without numba the benchmark still runs: NumPy paths only, no fused columns, a note says why."""
    monkeypatch.setattr(fast, "available", lambda: False)
    uniform, random = cases
    config = scaling.ScalingConfig(sizes=(4,), svd_max=4, dense_max=4, tridiagonal_max=4, budget=0.0,
                                   step_budget=0.0)
    result = scaling.run(uniform, random, config)
    rec = result.records[0]
    assert rec["step_fused"] is None and rec["floor_stream"] is None and rec["step_numpy"] > 0
    assert rec["floor"] == rec["floor_copy"] and rec["cheaper_uniform"]
    assert result.headline["target_met"] is None
    assert any("numba" in note for note in result.notes)
    assert "n/a" in scaling_report.markdown(result)
