"""Compiled loops of small [masses] scenes (numeric.compiled): the same trajectories as the NumPy
driver to rounding, for every step method with a loop, on a scene with every effect the generated
scalar_force carries (cubic springs, gravity, an expression force, ground acceleration) and dampers;
the disk cache (a second process compiles nothing); SciPy's DOP853 step sequence reproduced."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from helpers import scene_toml, system_of

from springchain.numeric.compiled.run import dop853, route
from springchain.numeric.run import registry
from springchain.numeric.run.grid import Grid
from springchain.numeric.run.implicit import ImplicitStep
from springchain.numeric.run.protocol import Kind, Options, record

pytest.importorskip("numba")

EVERYTHING = scene_toml(
    "everything", {"m": 1.0, "k": 2.0, "kappa": 0.7, "c": 0.05, "F0": 0.3, "Omega": 1.3, "g": 0.2, "A": 0.1},
    masses={"a": "m", "b": "2*m", "c1": "m", "d": "3*m"},
    springs=[{"between": ["wall", "a"], "k": "k", "k3": "kappa"}, {"between": ["a", "b"], "k": "k"},
             {"between": ["b", "c1"], "k": "2*k", "k3": "kappa"}, {"between": ["c1", "d"], "k": "k"}],
    dampers=[{"between": ["a", "b"], "c": "c"}, {"between": ["d", "wall"], "c": "c"}],
    forces=[{"on": "c1", "f": "F0*cos(Omega*t) + F0*exp(-t)"}],
    tables={"gravity": {"g": "g"}, "ground": {"acceleration": "A*sin(2*t)"}})

DUFFING_ONLY = scene_toml(
    "springy", {"m": 1.0, "k": 1.0, "kappa": 0.5},
    masses={"p": "m", "q": "2*m", "r": "m"},
    springs=[{"between": ["wall", "p"], "k": "k", "k3": "kappa"}, {"between": ["p", "q"], "k": "k", "k3": "kappa"},
             {"between": ["q", "r"], "k": "k"}])

STEP_METHODS = [m for m in registry.methods(Kind.STEP)
                if m.name not in ("expm", "chebyshev") and not isinstance(m, ImplicitStep)]
IMPLICIT_METHODS = [m for m in registry.methods(Kind.STEP) if isinstance(m, ImplicitStep)]


@pytest.fixture(autouse=True)
def _always_compile(monkeypatch):
    """Compile even the short runs of these tests (outside them, only runs that pay a first compile)."""
    import springchain.numeric.compiled.run as compiled_run

    monkeypatch.setattr(compiled_run, "COMPILE_MIN_EVALS", 0)


@pytest.fixture(scope="module")
def systems(scene_from_text):
    return {name: system_of(scene_from_text(text, f"{name}.toml"))[1]
            for name, text in (("everything", EVERYTHING), ("springy", DUFFING_ONLY))}


def _state(n, seed=3):
    rng = np.random.default_rng(seed)
    return 0.4 * rng.standard_normal(n), 0.4 * rng.standard_normal(n)


@pytest.mark.parametrize("scene", ["everything", "springy"])
@pytest.mark.parametrize("method", STEP_METHODS, ids=lambda m: m.name)
def test_compiled_loop_agrees_with_numpy_driver(systems, scene, method):
    system = systems[scene]
    if method.refusal(system):
        pytest.skip(method.refusal(system))
    assert route(system, method.integrator(system).__dict__.get("inner", method.integrator(system)), 10), \
        f"{method.name} on {scene} should run compiled"
    x0, v0 = _state(system.n)
    grid = Grid(0.01, 600, 7)
    fast = record(method, system, x0, v0, grid)
    slow = record(method.with_options(Options(compiled=False)), system, x0, v0, grid)
    scale = max(np.abs(slow.x).max(), np.abs(slow.v).max())
    assert np.abs(fast.x - slow.x).max() <= 1e-12 * scale
    assert np.abs(fast.v - slow.v).max() <= 1e-12 * scale
    assert fast.force_evals == slow.force_evals
    # a wrong force would show: the trajectory moved away from the start by far more than rounding
    assert np.abs(slow.x[-1] - x0).max() > 1e-3


@pytest.mark.parametrize("scene", ["everything", "springy"])
@pytest.mark.parametrize("method", IMPLICIT_METHODS, ids=lambda m: m.name)
def test_implicit_steps_compiled_agree_with_numpy(systems, scene, method):
    """Newmark/HHT run their whole loop compiled (dense LU once, Newton on cubic springs): the same frames
    and the same force evaluations as the NumPy driver, to rounding."""
    system = systems[scene]
    if method.refusal(system):
        pytest.skip(method.refusal(system))
    grid = Grid(0.05, 400, 7)
    assert method.compiled_loop(system, method.integrator(system), grid) == "newmark_loop"
    x0, v0 = _state(system.n)
    on = record(method, system, x0, v0, grid)
    off = record(method.with_options(Options(compiled=False)), system, x0, v0, grid)
    scale = max(np.abs(off.x).max(), np.abs(off.v).max())
    assert np.abs(on.x - off.x).max() <= 1e-12 * scale
    assert np.abs(on.v - off.v).max() <= 1e-12 * scale
    if system.linear:
        assert on.force_evals == off.force_evals
    else:  # Newton's stop at the rounding level may take one iteration more or less on a step
        assert abs(on.force_evals - off.force_evals) <= 0.01 * off.force_evals
    assert np.abs(on.x[-1] - x0).max() > 1e-3


def test_hht_alpha_reaches_the_compiled_loop(systems):
    """HHT's alpha (a run setting) changes the compiled run as it changes the NumPy one."""
    system = systems["springy"]
    x0, v0 = _state(system.n)
    grid = Grid(0.2, 300, 10)
    runs = {}
    for alpha in (-0.05, -0.3):
        hht = registry.method("hht", Options(settings=(("alpha", alpha),), progress=False))
        on = record(hht, system, x0, v0, grid)
        off = record(hht.with_options(Options(compiled=False, settings=(("alpha", alpha),))), system, x0, v0, grid)
        assert np.abs(on.x - off.x).max() <= 1e-12 * np.abs(off.x).max()
        runs[alpha] = on.x
    assert np.abs(runs[-0.05] - runs[-0.3]).max() > 1e-4


def test_tables_fall_back_to_numpy(scene_from_text, tmp_path):
    from helpers import write_scene

    from springchain.derive.scene import load_scene

    text = scene_toml("tab", {"m": 1.0, "k": 1.0}, masses={"a": "m", "b": "m"},
                      springs=[{"between": ["a", "b"], "k": "k"}], forces=[{"on": "a", "table": "f.csv"}])
    path = write_scene(tmp_path, "tab", text, {"f.csv": "t,f\n0,0\n1,1\n2,0\n"})
    system = system_of(load_scene(path))[1]
    verlet = registry.method("verlet")
    assert route(system, verlet.integrator(system).inner, 10) is None


def test_compiled_dop853_takes_scipys_steps(systems):
    from scipy.integrate import DOP853

    system = systems["everything"]
    n = system.n
    x0, v0 = _state(n)
    Ad = system.damping_rate_matrix()
    acc, ext = system.acceleration_fn, system.external_fn

    def rhs(t, y):
        return np.concatenate([y[n:], acc(y[:n]) + Ad @ y[n:] + np.reshape(ext(t), -1)])

    T, rtol, atol = 20.0, 1e-9, 1e-11
    solver = DOP853(rhs, 0.0, np.concatenate([x0, v0]), T, rtol=rtol, atol=atol)
    ts = []
    while solver.status == "running":
        solver.step()
        ts.append(solver.t)
    x, v, steps, evals = dop853(system, x0, v0, T, rtol, atol, max_steps=10_000)
    # the same steps: SciPy's initial step to rounding; after it the error norms (stage sums that cancel
    # from O(1) to O(rtol)) keep only about -log10(rtol) + 16 digits, so the summation order moves the
    # step ends by a relative 1e-7 (a different rule -- exponent, safety factor, norm -- moves them by %)
    assert steps.shape[0] == len(ts) > 20
    np.testing.assert_allclose(steps[0], ts[0], rtol=1e-13)
    np.testing.assert_allclose(steps, ts, rtol=1e-5)
    assert evals == solver.nfev
    np.testing.assert_allclose(np.concatenate([x, v]), solver.y, rtol=0, atol=1e-7)


_CHILD = textwrap.dedent("""
    import json, numpy as np
    from springchain._scenes import load
    from springchain._modules import system_of
    from springchain.numeric.run import registry
    from springchain.numeric.run.grid import Grid
    from springchain.numeric.run.protocol import record
    from springchain.numeric.compiled.cache import compiled
    system, _ = system_of(load("duffing"))
    run = record(registry.method("verlet"), system, np.full(3, 0.1), np.zeros(3), Grid(0.001, 200_000, 20_000))
    c = compiled(system)
    d = c.loop("verlet_loop")
    print(json.dumps({"compiled": sorted(c.compiled), "force_compiled": c.force_compiled,
                      "hits": sum(d.stats.cache_hits.values()),
                      "misses": sum(d.stats.cache_misses.values()), "x": run.x[-1].tolist(),
                      "seconds": c.compile_seconds}))
""")


def test_second_process_compiles_nothing(tmp_path):
    env = {**os.environ, "SPRINGCHAIN_CACHE": str(tmp_path / "cache"), "OPENBLAS_NUM_THREADS": "1"}
    runs = [json.loads(subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True,
                                      check=True).stdout.strip().splitlines()[-1]) for _ in range(2)]
    assert runs[0]["compiled"] == ["verlet_loop"] and runs[0]["misses"] == 1 and runs[0]["force_compiled"]
    assert runs[1]["compiled"] == [] and runs[1]["misses"] == 0 and runs[1]["hits"] == 1
    assert not runs[1]["force_compiled"]
    assert runs[0]["x"] == runs[1]["x"]
    assert list((tmp_path / "cache" / "compiled").glob("sc_*.py"))
    assert list((tmp_path / "cache" / "compiled").glob("loops_*.py"))


def test_scenes_share_one_compiled_loop(systems):
    """A loop is compiled once for every scene: the scene's force is its first argument (a cfunc of one
    type), so a second scene adds no signature, only its own force."""
    from springchain.numeric.compiled.cache import compiled

    method = registry.method("verlet")
    for name in ("everything", "springy"):
        system = systems[name]
        x0, v0 = _state(system.n)
        record(method, system, x0, v0, Grid(0.01, 50, 50))
    forces = {id(compiled(systems[name]).force) for name in ("everything", "springy")}
    assert len(forces) == 2
    assert len(compiled(systems["springy"]).loop("verlet_loop").signatures) == 1


def test_a_new_scene_takes_a_compiled_loop_from_ten_thousand_evaluations(monkeypatch, systems, scene_from_text):
    """A loop compiled already costs a new scene only its force's compile (~0.2 s): runs from
    FORCE_MIN_EVALS evaluations take it; a loop still to compile waits for COMPILE_MIN_EVALS."""
    import springchain.numeric.compiled.run as compiled_run

    method = registry.method("verlet")
    record(method, systems["springy"], *_state(3), Grid(0.01, 50, 50))  # the loop is compiled (eagerly)
    monkeypatch.setattr(compiled_run, "COMPILE_MIN_EVALS", 100_000)
    text = DUFFING_ONLY.replace('name = "springy"', 'name = "fresh_force"')
    assert text != DUFFING_ONLY
    system = system_of(scene_from_text(text, "fresh_force.toml"))[1]
    integ = method.integrator(system)
    assert compiled_run.min_evals(system, "verlet_loop") == compiled_run.FORCE_MIN_EVALS < 100_000
    assert route(system, integ, 10, evals=5_000) is None
    assert route(system, integ, 10, evals=20_000) == "verlet_loop"
    record(method, system, *_state(3), Grid(0.01, 20_000, 100))
    assert compiled_run.min_evals(system, "verlet_loop") == 0 and route(system, integ, 10, evals=10) == "verlet_loop"


@pytest.mark.parametrize("name", ["dprkn6", "dprkn8", "dprkn12"])
def test_compiled_rkn_pairs_agree_with_numpy(systems, name):
    """Same pair, same step control: the trajectories agree far inside the tolerance (the step sequences
    may part where an error norm within rounding of a decision flips it)."""
    system = systems["springy"]
    method = registry.method(name)
    x0, v0 = _state(system.n)
    t = np.linspace(0.0, 20.0, 21)
    fast = method.solve(system, x0, v0, t, 1e-10, 1e-12)
    slow = method.with_options(Options(compiled=False)).solve(system, x0, v0, t, 1e-10, 1e-12)
    assert np.abs(fast.x - slow.x).max() <= 1e-8 * np.abs(slow.x).max()
    assert abs(fast.force_evals - slow.force_evals) <= 0.1 * slow.force_evals


def test_compiled_dop853_dense_output_matches_scipy(systems):
    """dop853-compiled records like solve_ivp(t_eval=...): SciPy's dense output, the same evaluations."""
    from scipy.integrate import solve_ivp

    system = systems["everything"]
    n = system.n
    x0, v0 = _state(n, seed=5)
    Ad = system.damping_rate_matrix()
    acc, ext = system.acceleration_fn, system.external_fn

    def rhs(t, y):
        return np.concatenate([y[n:], acc(y[:n]) + Ad @ y[n:] + np.reshape(ext(t), -1)])

    t = np.linspace(0.0, 15.0, 301)
    method = registry.method("dop853-compiled", Options(rtol=1e-9, atol=1e-12, progress=False))
    assert method.refusal(system) is None
    run = record(method, system, x0, v0, Grid(t[1] - t[0], 300))
    sol = solve_ivp(rhs, (0.0, 15.0), np.concatenate([x0, v0]), method="DOP853", t_eval=run.t, rtol=1e-9, atol=1e-12)
    assert run.force_evals == sol.nfev
    np.testing.assert_allclose(run.x, sol.y[:n].T, rtol=0, atol=1e-10)
    np.testing.assert_allclose(run.v, sol.y[n:].T, rtol=0, atol=1e-10)
    assert np.abs(run.x[-1] - x0).max() > 1e-2


def test_compiled_dop853_refuses_what_it_cannot_compile(scene_from_text, tmp_path):
    from helpers import write_scene

    from springchain.derive.scene import load_scene

    text = scene_toml("tab2", {"m": 1.0, "k": 1.0}, masses={"a": "m", "b": "m"},
                      springs=[{"between": ["a", "b"], "k": "k"}], forces=[{"on": "a", "table": "f.csv"}])
    path = write_scene(tmp_path, "tab2", text, {"f.csv": "t,f\n0,0\n1,1\n2,0\n"})
    system = system_of(load_scene(path))[1]
    why = registry.method("dop853-compiled").refusal(system)
    assert why and "dop853" in why


POTENTIALS = scene_toml(
    "potmix", {"m": 1.0, "k": 1.0, "alpha": 0.25, "a": 1.0, "b": 1.7, "D": 2.0, "w": 1.3, "g": 0.3,
               "eps": 0.5, "r0": 1.1},
    masses={"p": "m", "q": "2*m", "r": "m", "s": "1.5*m"},
    springs=[{"between": ["wall", "p"], "potential": "a/b*exp(-b*d) + a*d"},
             {"between": ["p", "q"], "potential": "D*(1 - exp(-w*d))**2"},
             {"between": ["q", "r"], "potential": "k*d**2/2 + alpha*d**3/3"},
             {"between": ["r", "s"], "k": "k"},
             {"between": ["s", "wall"], "potential": "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"}],
    tables={"gravity": {"g": "g"}})


def test_potential_scenes_get_a_scalar_force(scene_from_text):
    """Toda, Morse, FPUT and Lennard-Jones springs (with a plain spring and gravity): scalar_force equals
    the NumPy acceleration on random states, down to extensions of 1e-9 (the same stable forms), and the
    compiled loops agree with the NumPy driver."""
    module, system = system_of(scene_from_text(POTENTIALS, "potmix.toml"))
    assert system.has("scalar_force") and route(system, registry.method("verlet").integrator(system), 10)
    rng = np.random.default_rng(11)
    p = np.array([float(system.params[q]) for q in module.PARAMETERS])
    x_eq = np.asarray(module.equilibrium(**module.DEFAULTS))
    worst = 0.0
    for _ in range(200):
        x = x_eq + rng.uniform(-0.3, 0.3, system.n) * 10.0 ** rng.uniform(-9, 0)
        out = np.empty(system.n)
        module.scalar_force(x, 0.0, out, p)
        ref = system.acceleration_fn(x[:, None])[:, 0]
        worst = max(worst, float(np.max(np.abs(out - ref)) / np.max(np.abs(ref))))
    assert worst <= 1e-14
    x0, v0 = x_eq + 0.2 * rng.standard_normal(system.n), 0.2 * rng.standard_normal(system.n)
    for name in ("verlet", "blanes-moan6", "rk4"):
        m = registry.method(name, Options(progress=False))
        grid = Grid(0.01, 500, 5)
        on = record(m, system, x0, v0, grid)
        off = record(m.with_options(Options(compiled=False, progress=False)), system, x0, v0, grid)
        assert np.abs(on.x - off.x).max() <= 1e-12 * np.abs(off.x).max()
        assert np.abs(on.x[-1] - x0).max() > 1e-2


SINGULAR = scene_toml(
    "singular", {"m": 1.0, "k": 1.0, "c": 0.1, "r0": 1.0},
    masses={"p": "m", "q": "m"},
    springs=[{"between": ["wall", "p"], "k": "k"},
             {"between": ["p", "q"], "potential": "k*d**2/2 + c/(r0 + d) + c/(r0 - d)"}])


def test_a_force_that_divides_by_zero_gives_what_numpy_gives(scene_from_text, capfd):
    """The compiled force uses NumPy's error model: a division by zero (here at the extension d = ±r0)
    gives inf or nan frames as on the NumPy path, and nothing is printed (a cfunc cannot raise)."""
    _, system = system_of(scene_from_text(SINGULAR, "singular.toml"))
    x0, v0 = np.array([0.0, 1.0]), np.zeros(2)
    m = registry.method("verlet", Options(progress=False))
    grid = Grid(0.01, 20, 20)
    with np.errstate(all="ignore"):
        on = record(m, system, x0, v0, grid)
        off = record(m.with_options(Options(compiled=False, progress=False)), system, x0, v0, grid)
    assert not np.isfinite(on.x[1:]).all() and not np.isfinite(off.x[1:]).all()
    assert np.array_equal(np.isfinite(on.x), np.isfinite(off.x))
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy-driver", "compiled-loop"])
def test_a_run_that_diverges_says_so_in_one_note(tmp_path, capfd, monkeypatch, compiled):
    """Started at the singular extension, Verlet's state is inf/nan from the first step: the command says
    so in one note (stdout, the NPZ's notes) and NumPy prints no warning, on either path."""
    import springchain.numeric.compiled.run as compiled_run
    from springchain.cli import main

    if not compiled:
        monkeypatch.setattr(compiled_run, "COMPILE_MIN_EVALS", 10**12)
        monkeypatch.setattr(compiled_run, "FORCE_MIN_EVALS", 10**12)
    path = tmp_path / "singular.toml"
    path.write_text(SINGULAR + '\n[initial]\nx = [0.0, 1.0]\nv = [0.0, 0.0]\n')
    assert main(["simulate", str(path), "--method", "verlet", "--steps", "2000", "--record-every", "100",
                 "--out", str(tmp_path / "o")]) == 0
    out, err = capfd.readouterr()
    assert "note: verlet: the state is not finite at t = 10 s (frame 1, the first recorded frame" in out, out
    assert "Warning" not in err, err
    notes = np.load(tmp_path / "o" / "singular.npz")["notes"].tolist()
    assert len(notes) == 1 and notes[0].startswith("verlet: the state is not finite")


def test_a_chain_that_diverges_says_so_in_one_note(tmp_path, capfd, repo_root):
    """The bundled FPUT-alpha chain started at 40 times its amplitude leaves the cubic potential's well
    (V is unbounded below) and overflows: the streamed [chain] run says so in one note, also in the NPZ."""
    from springchain.cli import main

    text = (repo_root / "scenes" / "fput_alpha.toml").read_text()
    big = text.replace('x = "sin(pi*(i + 1)/(n + 1))"', 'x = "40*sin(pi*(i + 1)/(n + 1))"')
    assert big != text
    path = tmp_path / "fput_big.toml"
    path.write_text(big.replace('name = "fput_alpha"', 'name = "fput_big"'))
    assert main(["simulate", str(path), "--method", "verlet", "--steps", "2000", "--out", str(tmp_path / "o")]) == 0
    out, err = capfd.readouterr()
    assert "note: verlet: the energy is not finite at t = " in out, out
    assert "Warning" not in err, err
    notes = np.load(tmp_path / "o" / "fput_big.npz")["notes"].tolist()
    assert len(notes) == 1 and notes[0].startswith("verlet: the energy is not finite")
