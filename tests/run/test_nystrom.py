"""The embedded Runge–Kutta–Nyström pairs (dprkn6, dprkn8, dprkn12).

Tables: order conditions exact to 1e-14 at the declared orders and failing one order higher,
corrupted tables refused by name, floats equal to the exact values. Steps: convergence slopes
of fixed steps against the declared order, on the harmonic oscillator (exact cos/sin) and on a
nonlinear pendulum (against SciPy's DOP853 at rtol 1e-13). Adaptive runs: accuracy follows the
tolerance on the seed scene (against the modal solution) and on the Duffing chain (against
DOP853); dampers refused; the command line runs them by name and writes x_<name>.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from springchain.numeric.errors import RunRefused
from springchain.numeric.integrators import Problem
from springchain.numeric.integrators.dprkn6 import DPRKN6_TABLE
from springchain.numeric.integrators.dprkn8 import DPRKN8_TABLE
from springchain.numeric.integrators.dprkn12 import DPRKN12_TABLE
from springchain.numeric.integrators.nystrom import rkn_step
from springchain.numeric.integrators.nystrom_tables import NystromTable, q
from springchain.numeric.run import registry
from springchain.numeric.run.protocol import Kind

ADAPTIVE = registry.classes(Kind.ADAPTIVE)

TABLES = {"dprkn6": DPRKN6_TABLE, "dprkn8": DPRKN8_TABLE, "dprkn12": DPRKN12_TABLE}
SCENES = Path(__file__).resolve().parents[2] / "scenes"


@pytest.mark.parametrize("name", sorted(TABLES))
def test_order_conditions_hold_at_the_declared_orders(name):
    t = TABLES[name]
    for weights, order in (("main", t.order), ("embedded", t.embedded_order)):
        res = t.residuals(weights, order)
        assert len(res) > 2 * order and max(res.values()) < 1e-14, (weights, order)
    # one order higher, some condition fails clearly: the orders are what is declared
    assert max(t.residuals("main", t.order + 1).values()) > 1e-8
    assert max(t.residuals("embedded", t.embedded_order + 1).values()) > 1e-8


@pytest.mark.parametrize("name", sorted(TABLES))
def test_float_arrays_match_the_exact_tables(name):
    t = TABLES[name]
    arr = t.arrays
    s = t.stages
    assert arr["A"].shape == (s, s) and np.all(np.triu(arr["A"]) == 0)
    # row sums c²/2, Σb = 1/2, Σb' = 1 in floats; error weights sum to 0 (both solutions are consistent)
    assert np.allclose(arr["A"].sum(axis=1), arr["c"] ** 2 / 2, rtol=0, atol=1e-14)
    assert abs(math.fsum(arr["b"]) - 0.5) < 1e-15 and abs(math.fsum(arr["bp"]) - 1.0) < 1e-15
    assert abs(math.fsum(arr["e"])) < 1e-15 and abs(math.fsum(arr["ep"])) < 1e-15
    assert ADAPTIVE[name].order == t.order and ADAPTIVE[name].table is t and not ADAPTIVE[name].symplectic


def test_declared_stage_counts_and_published_nodes():
    assert [TABLES[n].evals_per_step for n in ("dprkn6", "dprkn8", "dprkn12")] == [5, 8, 17]
    assert DPRKN6_TABLE.arrays["c"][1] == pytest.approx((209 - math.sqrt(8581)) / 900, rel=1e-15)
    assert DPRKN12_TABLE.arrays["c"][14] == pytest.approx(8437 / 8926, rel=1e-15)


def test_corrupted_tables_are_refused_by_name():
    t = DPRKN8_TABLE
    rows = list(t.a)
    rows[4] = (rows[4][0] + q("1/1000000000"),) + rows[4][1:]
    with pytest.raises(ValueError, match="dprkn8.*row 5"):
        replace(t, a=tuple(rows))
    bp = list(t.bp)
    bp[2] += q("1/1000000000")
    bp[3] -= q("1/1000000000")  # Σb' still 1: only the higher conditions see it
    with pytest.raises(ValueError, match="dprkn8.*main weights"):
        replace(t, bp=tuple(bp))
    with pytest.raises(ValueError, match="declared order 6"):
        replace(t, order=6, embedded_order=5)
    with pytest.raises(ValueError, match="dprkn12.*first-same-as-last"):
        replace(DPRKN12_TABLE, fsal=True)  # its last stage is not at the new state
    with pytest.raises(ValueError, match="explicit"):
        NystromTable("bad", (0, 1), ((), ()), (q("1/2"), 0), (0, 1), (q("1/2"), 0), (0, 1), order=2,
                     embedded_order=1)


def _fixed_step_run(table, accel, x0, v0, t_end, n):
    tab = table.arrays
    h = t_end / n
    x, v = np.array([[x0]], float), np.array([[v0]], float)
    K = np.empty((table.stages, 1, 1))

    def force(xx, tt):
        return accel(xx)

    for i in range(n):
        K[0] = force(x, i * h)
        x, v, _, _ = rkn_step(tab, force, x, v, K, i * h, h)
    return float(x[0, 0]), float(v[0, 0])


def _slope(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


# steps chosen so that errors stay well above rounding (≥ 1e-12) and in the asymptotic range
STEPS = {"dprkn6": (40, 56, 80, 112), "dprkn8": (24, 32, 44, 60), "dprkn12": (14, 18, 24, 32)}


@pytest.mark.parametrize("name", sorted(TABLES))
def test_convergence_slope_harmonic_oscillator(name):
    """x'' = -ω²x, ω = 3, over T = 10: error in x and v against cos/sin, slope = declared order."""
    t = TABLES[name]
    w, T = 3.0, 10.0
    hs, errs = [], []
    for n in STEPS[name]:
        x, v = _fixed_step_run(t, lambda x: -w * w * x, 1.0, 0.0, T, n)
        errs.append(max(abs(x - math.cos(w * T)), abs(v + w * math.sin(w * T)) / w))
        hs.append(T / n)
    assert min(errs) > 1e-13, errs
    assert abs(_slope(hs, errs) - t.order) < 0.6, (_slope(hs, errs), errs)


NONLINEAR_STEPS = {"dprkn6": (40, 56, 80, 112), "dprkn8": (24, 32, 48, 64), "dprkn12": (16, 24, 32)}


def _eighths(table, accel, x0, v0, t_end, n):
    """States at t = T/8, 2T/8, …, T of a fixed-step run (n divisible by 8), shape (8, 2)."""
    tab = table.arrays
    h = t_end / n
    x, v = np.array([[x0]], float), np.array([[v0]], float)
    K = np.empty((table.stages, 1, 1))
    out = []
    for i in range(n):
        K[0] = accel(x)
        x, v, _, _ = rkn_step(tab, lambda xx, tt: accel(xx), x, v, K, i * h, h)
        if (i + 1) % (n // 8) == 0:
            out.append((x[0, 0], v[0, 0]))
    return np.array(out)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_convergence_slope_nonlinear(name):
    """x'' = -sin x - x³ from x = 1 over T = 10 (every nonlinear order condition is exercised):
    largest error over eight times against the same pair at 1600 steps (rounding-level there),
    slope = declared order within 1.1 (the leading error constant is small for 8(6), so the
    next term still shows at these steps)."""
    t = TABLES[name]

    def accel(x):
        return -np.sin(x) - x**3

    ref = _eighths(t, accel, 1.0, 0.0, 10.0, 1600)
    hs, errs = [], []
    for n in NONLINEAR_STEPS[name]:
        errs.append(float(np.max(np.abs(_eighths(t, accel, 1.0, 0.0, 10.0, n) - ref))))
        hs.append(10.0 / n)
    assert min(errs) > 5e-14, errs
    assert abs(_slope(hs, errs) - t.order) < 1.1, (_slope(hs, errs), errs)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_adaptive_accuracy_on_the_seed_scene(name):
    """Against the exact modal solution: error within a small factor of the tolerance, and smaller at a tighter one."""
    import springchain.generated.seed as seed_module
    from springchain.numeric.exact.modal import ModalSolution
    from springchain.numeric.modes.spectrum import spectrum
    from springchain.numeric.system import System

    system = System.from_module(seed_module)
    x0, v0 = np.array([0.3, -0.1, 0.2]), np.array([0.0, 0.4, -0.2])
    t = np.linspace(0.0, 100.0, 11)
    sol = ModalSolution.from_initial(spectrum(system.masses, system.spring_ends, system.stiffness), x0, v0)
    xr, vr = sol.at(t)
    errs = []
    for tol in (1e-6, 1e-10):
        res = ADAPTIVE[name]().solve(Problem.from_system(system), x0, v0, t, tol, tol)
        assert res.x.shape == (11, 3, 1) and np.allclose(res.x[0, :, 0], x0, rtol=0, atol=0)
        errs.append(float(np.max(np.abs(res.x[..., 0] - xr))))
        assert res.force_evals >= res.steps * TABLES[name].evals_per_step
    assert errs[0] < 100 * 1e-6 and errs[1] < 100 * 1e-10 and errs[1] < errs[0] / 100, errs


def test_adaptive_on_duffing_against_dop853_and_batch():
    import springchain as sc
    from springchain._modules import system_of

    scene = sc.load("duffing")
    system, _ = system_of(scene)
    x0 = np.stack([np.asarray(scene.x0, float), 0.5 * np.asarray(scene.x0, float)], axis=1)
    v0 = np.stack([np.asarray(scene.v0, float), np.zeros(3)], axis=1)
    t = np.linspace(0.0, 50.0, 6)
    ref = solve_ivp(lambda _, y: np.concatenate([y[6:], system.acceleration_fn(y[:6].reshape(3, 2)).ravel()]),
                    (0, 50), np.concatenate([x0.ravel(), v0.ravel()]), method="DOP853", t_eval=t,
                    rtol=1e-13, atol=1e-14)
    xr = ref.y[:6].T.reshape(-1, 3, 2)
    for name in TABLES:
        res = ADAPTIVE[name]().solve(Problem.from_system(system), x0, v0, t, 1e-10, 1e-10)
        assert res.x.shape == (6, 3, 2)
        assert np.max(np.abs(res.x - xr)) < 1e-7, name


def test_dampers_and_bad_tolerances_are_refused():
    prob = Problem(lambda x: -x, damping=lambda v: -0.1 * v)
    with pytest.raises(RunRefused, match="dampers"):
        ADAPTIVE["dprkn8"]().solve(prob, np.ones(1), np.zeros(1), np.array([0.0, 1.0]), 1e-6, 1e-6)
    with pytest.raises(RunRefused, match="rtol"):
        ADAPTIVE["dprkn8"]().solve(Problem(lambda x: -x), np.ones(1), np.zeros(1), np.array([0.0, 1.0]), 0.0, 1e-6)


def test_external_force_enters_the_stages():
    """x'' = -x + cos(2t): exact x = (4/3)… compared with a tight DOP853 run."""
    prob = Problem(lambda x: -x, external=lambda t: np.array([math.cos(2 * t)]))
    t = np.array([0.0, 5.0])
    res = ADAPTIVE["dprkn12"]().solve(prob, np.array([0.5]), np.array([0.0]), t, 1e-12, 1e-12)
    ref = solve_ivp(lambda tt, y: [y[1], -y[0] + math.cos(2 * tt)], (0, 5), [0.5, 0.0], rtol=1e-13, atol=1e-14,
                    method="DOP853")
    assert abs(res.x[-1, 0, 0] - ref.y[0, -1]) < 1e-10


@pytest.mark.parametrize("name", ["dprkn8", "dprkn12"])
def test_simulate_command_runs_the_pairs(tmp_path, name):
    from springchain.cli import main

    out = tmp_path / "out"
    assert main(["simulate", str(SCENES / "duffing.toml"), "--method", name, "--no-figures", "--out", str(out)]) == 0
    npz = [p for p in out.rglob("*.npz")]
    assert npz, list(out.rglob("*"))
    with np.load(npz[0]) as data:
        assert f"x_{name}" in data.files
        x = data[f"x_{name}"]
    assert np.all(np.isfinite(x)) and np.allclose(x[0], [0.8, 0.0, -0.4])


def test_simulate_refuses_the_pairs_on_damped_scenes(tmp_path):
    from springchain.cli import main

    damped = [p for p in sorted(SCENES.glob("*.toml")) if "damp" in p.read_text(encoding="utf-8")]
    assert damped
    assert main(["simulate", str(damped[0]), "--method", "dprkn8", "--no-figures", "--out", str(tmp_path / "o")]) == 2


def test_plan_covers_the_pairs():
    import springchain.generated.seed as seed_module
    from springchain.numeric.plan.planner import Planner
    from springchain.numeric.system import System

    system = System.from_module(seed_module)
    planner = Planner.for_system(system, np.array([0.3, -0.1, 0.2]), np.array([0.0, 0.4, -0.2]), 20.0, 0.1)
    plan = planner.plan(1e-6)
    names = {c.name for c in (*plan.candidates, *plan.unreachable)}
    assert {"dprkn6", "dprkn8", "dprkn12", "dop853"} <= names
    for name in ("dprkn8", "dprkn12"):
        law = planner.adaptive[registry.method(name)]
        assert law.error(1e-8, 20.0) < law.error(1e-5, 20.0)  # calibrated: tighter rtol, smaller error


def test_bench_duffing_interpolates_costs_on_the_lower_envelope():
    from benchmark_scripts import load

    duffing = load("duffing")
    TARGET, cost_at, ratio_table = duffing.TARGET, duffing.cost_at, duffing.ratio_table

    runs = [{"error": 1e-3, "evals": 100, "seconds": 1.0}, {"error": 2e-3, "evals": 150, "seconds": 1.5},
            {"error": 1e-5, "evals": 400, "seconds": 4.0}]
    # 1e-4 lies half-way (in log) between the 100-eval and 400-eval runs: cost √(100·400) = 200
    assert cost_at(runs, 1e-4, "evals") == pytest.approx(200.0)
    assert cost_at(runs, 1e-3, "evals") == 100 and cost_at(runs, 1e-6, "evals") is None
    dop = [{"error": 10.0 ** -k, "evals": 1000 * k, "seconds": float(k)} for k in range(2, 12)]
    fast = [{"error": 10.0 ** -k, "evals": 250 * k, "seconds": k / 2.0} for k in range(2, 12)]
    rows = ratio_table({"dop853": dop, "dprkn12": fast})
    assert all(r["best"] == "dprkn12" for r in rows)
    assert all(r["methods"]["dprkn12"]["evals_ratio"] == pytest.approx(4.0) for r in rows)
    # 4× in evaluations but only 2× in seconds: the target needs both
    assert TARGET == 3.0 and not any(r["met"] for r in rows)
