"""Effects (issue 3): dampers, forces, gravity, cubic springs, rings and chains.

Every trajectory is checked against an independent reference: a first-order
system assembled here, from the scene file's own numbers (parsed with tomllib
and evaluated with SymPy in the test), integrated by solve_ivp DOP853 at rtol 1e-12.
"""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import sympy

import helpers
from helpers import TomlScene, chain_toml
from springchain._modules import derive, load_module
from springchain.derive.scene import load_scene
from springchain.numeric.run.simulate import run_methods, stream_methods
from springchain.numeric.system import System

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


# -- an independent reference, built from the TOML text only ------------------------------------
def reference_rhs(path: Path):
    """RHS f(t, z) of z = (x, v) built from the raw scene: no springchain code involved."""
    toml = TomlScene.read(path)
    data, num = toml.data, toml.value
    idx = toml.mass_index()
    m = np.array([num(e) for e in data["masses"].values()])
    n = len(m)
    springs = [([idx[e] for e in s["between"]], num(s["k"]), num(s.get("k3", 0)))
               for s in data.get("springs", [])]
    dampers = [([idx[e] for e in d["between"]], num(d["c"])) for d in data.get("dampers", [])]
    forces = [(idx[f["on"]], toml.of_t(f["f"])) for f in data.get("forces", [])]
    g = num(data["gravity"]["g"]) if "gravity" in data else 0.0

    def rhs(tt, z):
        x, v = z[:n], z[n:]
        f = m * g
        for (a, b), k, k3 in springs:
            d = (x[a] if a >= 0 else 0.0) - (x[b] if b >= 0 else 0.0)
            s = k * d + k3 * d**3
            if a >= 0:
                f[a] -= s
            if b >= 0:
                f[b] += s
        for (a, b), c in dampers:
            dv = (v[a] if a >= 0 else 0.0) - (v[b] if b >= 0 else 0.0)
            if a >= 0:
                f[a] -= c * dv
            if b >= 0:
                f[b] += c * dv
        for on, fn in forces:
            f[on] += float(fn(tt))
        return np.concatenate([v, f / m])

    return rhs, n


def dop853_scaled(rhs, n, x0, v0, t):
    """DOP853 at rtol 1e-12, atol 1e-14 relative to the initial state's size."""
    return helpers.dop853(rhs, n, x0, v0, t, atol=1e-14 * max(1.0, np.max(np.abs(x0)), np.max(np.abs(v0))))


def scene_and_system(path: Path) -> tuple[object, System]:
    scene = load_scene(path)
    return scene, helpers.system_of(scene)[1]


EXACT_SCENES = ["building", "hanging", "ring4", "seed"]


@pytest.mark.parametrize("name", EXACT_SCENES)
def test_exact_solution_matches_independent_reference(name):
    scene, system = scene_and_system(SCENES / f"{name}.toml")
    rng = np.random.default_rng(1)
    x0 = scene.x0 + 0.01 * rng.standard_normal(scene.n)
    v0 = scene.v0 + 0.01 * rng.standard_normal(scene.n)
    steps = 400
    runs = run_methods(system, x0, v0, scene.dt, steps, ["modal"])
    rhs, n = reference_rhs(SCENES / f"{name}.toml")
    xr, vr = dop853_scaled(rhs, n, x0, v0, runs["modal"].t)
    scale = max(np.max(np.abs(xr)), 1e-3)
    assert np.max(np.abs(runs["modal"].x - xr)) <= 1e-8 * scale
    vscale = max(np.max(np.abs(vr)), 1e-3)
    assert np.max(np.abs(runs["modal"].v - vr)) <= 1e-8 * vscale


@pytest.mark.parametrize("name", ["building", "hanging", "ring4", "duffing"])
def test_verlet_second_order_against_reference(name):
    """Verlet (with the damping/forcing splitting where the scene needs it) converges at order 2."""
    scene, system = scene_and_system(SCENES / f"{name}.toml")
    rhs, n = reference_rhs(SCENES / f"{name}.toml")
    x0 = scene.x0 + 0.05
    v0 = scene.v0
    T = 200 * scene.dt
    errs = []
    hs = [scene.dt, scene.dt / 2, scene.dt / 4]
    for h in hs:
        steps = int(round(T / h))
        run = run_methods(system, x0, v0, h, steps, ["verlet"])["verlet"]
        xr, _ = dop853_scaled(rhs, n, x0, v0, run.t)
        errs.append(np.max(np.abs(run.x - xr)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 2.0) < 0.2, (errs, slope)


# -- generated code contains exactly the declared effects -----------------------------------------
EFFECT_MARKERS = {
    "damper": ("def damping_matrix", "def damping_acceleration", "DAMPER_ENDS"),
    "force": ("def external_acceleration", "FORCING_HARMONIC"),
    "gravity": ("def gravity_forces",),
    "cubic": ("def cubic_constants", "**3"),
    "rayleigh": ("def rayleigh_coefficients",),
    "modal_damping": ("def modal_damping_ratios", "def _modal_damping_matrix"),
}


@pytest.mark.parametrize("name, effects", [("seed", set()), ("ring4", set()), ("building", {"damper", "force"}),
                                           ("hanging", {"gravity"}), ("duffing", {"cubic"}),
                                           ("building_rayleigh", {"force", "rayleigh"})])
def test_generated_source_has_exactly_the_declared_effects(name, effects):
    source = (ROOT / "generated" / f"{name}.py").read_text()
    for effect, markers in EFFECT_MARKERS.items():
        present = [mk in source for mk in markers]
        if effect == "damper" and "rayleigh" in effects:  # the damping matrix, without dashpots
            assert "DAMPER_ENDS" not in source and "def damping_matrix" in source
        elif effect in effects:
            assert all(present), (effect, markers)
        else:
            assert not any(present), (effect, markers)


def _with(text: str, extra: str) -> str:
    return text.replace("[initial]", extra + "\n[initial]")


def test_adding_a_damper_adds_only_damping_code():
    base = (SCENES / "seed.toml").read_text()
    damped = _with(base.replace("[parameters]", "[parameters]\nc = 0.1"),
                   '[[dampers]]\nbetween = ["m1", "wall"]\nc = "c"\n')
    a = derive(load_scene("seed.toml", text=base)).source.splitlines()
    b = derive(load_scene("seed.toml", text=damped)).source.splitlines()
    added = [line for line in b if line not in a]
    removed = [line for line in a if line not in b]
    # only the header/hash, the parameter lists and the damping code change
    assert any("def damping_acceleration(_v, c, k, m)" in line for line in added)
    assert not any("external" in line or "gravity" in line or "cubic" in line for line in added)
    for line in removed:  # lines that list the parameters change because c is a new parameter
        assert "SCENE_SHA256" in line or "GENERATED" in line or "def " in line or "PARAMETERS" in line \
            or "DEFAULTS" in line or "EFFECTS" in line or "k=k, m=m" in line, line


# -- exact forms at singular points -----------------------------------------------------------------
RESONANT = """
name = "resonant"
[parameters]
m = 1.0
k = 4.0
F0 = 0.5
[masses]
bob = "m"
[[springs]]
between = ["bob", "wall"]
k = "k"
[[forces]]
on = "bob"
f = "F0*cos(2*t)"
[initial]
x = [0.0]
v = [0.0]
[simulation]
dt = 0.01
steps = 2000
"""


def test_undamped_exact_resonance_grows_like_t_sin():
    """Ω = ω exactly: x(t) = F0 t sin(ωt) / (2 m ω), no division by zero."""
    scene = load_scene("resonant.toml", text=RESONANT)
    module, _ = load_module(scene)
    system = System.from_module(module)
    run = run_methods(system, scene.x0, scene.v0, scene.dt, scene.steps, ["modal"])["modal"]
    t = run.t
    expected = 0.5 * t * np.sin(2 * t) / (2 * 1.0 * 2.0)
    assert np.all(np.isfinite(run.x))
    assert np.max(np.abs(run.x[:, 0] - expected)) <= 1e-10 * np.max(np.abs(expected))


FALLING = """
name = "falling"
[parameters]
m = 2.0
k = 3.0
g = 9.81
[masses]
p1 = "m"
p2 = "m"
[[springs]]
between = ["p1", "p2"]
k = "k"
[gravity]
g = "g"
[initial]
x = [0.1, -0.2]
v = [0.5, 0.1]
[simulation]
dt = 0.05
steps = 400
"""


def test_free_piece_under_gravity_accelerates_exactly():
    scene = load_scene("falling.toml", text=FALLING)
    module, _ = load_module(scene)
    system = System.from_module(module)
    run = run_methods(system, scene.x0, scene.v0, scene.dt, scene.steps, ["modal", "verlet"])
    t = run["modal"].t
    xcm = run["modal"].x.mean(axis=1)
    expected = scene.x0.mean() + scene.v0.mean() * t + 0.5 * 9.81 * t**2
    assert np.max(np.abs(xcm - expected)) <= 1e-10 * np.max(np.abs(expected))
    # Verlet integrates a constant force exactly, so the centre of mass matches too
    assert np.max(np.abs(run["verlet"].x.mean(axis=1) - expected)) <= 1e-9 * np.max(np.abs(expected))


def test_hanging_chain_at_static_equilibrium_stays_there():
    scene, system = scene_and_system(SCENES / "hanging.toml")
    K = np.asarray(system.module.stiffness_matrix(**system.params))
    g = np.asarray(system.module.gravity_forces(**system.params))
    x_eq = np.linalg.solve(K, g)
    run = run_methods(system, x_eq, np.zeros(3), 0.01, 500, ["modal", "verlet"])
    for r in run.values():
        assert np.max(np.abs(r.x - x_eq)) <= 1e-10 * np.max(np.abs(x_eq))
    # the reported sag agrees
    from springchain.derive.model import Model
    from springchain.derive.report import static_equilibrium

    sag = static_equilibrium(Model(scene))
    values = {sympy.Symbol(k, positive=True): v for k, v in scene.parameters.items()}
    assert np.allclose([float(e.subs(values)) for e in sag], x_eq, rtol=1e-12)


def test_damped_energy_balance():
    """E(T) − E(0) = −∫ vᵀ C v dt + ∫ vᵀ F dt (the dampers' and forces' work), on the exact solution."""
    scene, system = scene_and_system(SCENES / "building.toml")
    h, steps = 0.0005, 8000
    run = run_methods(system, np.array([0.01, -0.02, 0.03]), np.zeros(3), h, steps, ["modal"])["modal"]
    C = np.asarray(system.module.damping_matrix(**system.params))
    E = system.energy(run.x.T, run.v.T)
    dissipated = np.einsum("si,ij,sj->s", run.v, C, run.v)
    F = np.stack([system.module.external_acceleration(t, **system.params) * system.masses for t in run.t])
    power = np.einsum("si,si->s", run.v, F)
    balance = scipy.integrate.cumulative_trapezoid(power - dissipated, run.t, initial=0.0)
    assert np.max(np.abs((E - E[0]) - balance)) <= 1e-5 * np.max(np.abs(E))


def test_nonlinear_scene_refuses_modal():
    from springchain.cli import main

    assert main(["simulate", str(SCENES / "duffing.toml"), "--method", "modal", "--no-figures",
                 "--out", "/nonexistent-never-written"]) == 2


# -- chains -------------------------------------------------------------------------------------------
def chain_scene(n, left, right, mass="m", k="k"):
    return chain_toml(n, left, right, mass=mass, k=k, simulation={"dt": 0.1, "steps": 1000, "record_every": 100})


@pytest.mark.parametrize("n", [1, 2, 7, 50])
@pytest.mark.parametrize("ends", [("free", "free"), ("wall", "wall"), ("wall", "free"), ("free", "wall"),
                                  ("ring", "ring")])
def test_uniform_chain_closed_forms_match_eigensolver(n, ends):
    if ends[0] == "ring" and n < 3:
        pytest.skip("a ring needs three masses")
    scene = load_scene("ch.toml", text=chain_scene(n, *ends))
    module, _ = load_module(scene)
    p = dict(module.DEFAULTS)
    closed = np.sort(module.omega2(**p, n=n))
    m = module.masses(**p, n=n)
    if ends[0] == "ring":
        ref = scipy.linalg.eigh(module.stiffness_matrix(**p, n=n), np.diag(m), eigvals_only=True)
    else:
        diag, off = module.stiffness_bands(**p, n=n)
        r = 1 / np.sqrt(m)
        ref = scipy.linalg.eigh_tridiagonal(diag * r * r, off * r[:-1] * r[1:], eigvals_only=True)
    scale = 4 * 2.3 / 1.7
    assert np.allclose(np.sort(ref), closed, rtol=1e-12, atol=1e-12 * scale)


def test_chain_stencil_equals_dense_acceleration():
    scene = load_scene("ch.toml", text=chain_scene(9, "wall", "free", mass="m*(1 + i % 2)", k="k*(1 + 0.1*i)"))
    module, _ = load_module(scene)
    p = dict(module.DEFAULTS)
    K = module.stiffness_matrix(**p, n=9)
    m = module.masses(**p, n=9)
    x = np.random.default_rng(0).standard_normal((9, 4))
    assert np.allclose(module.acceleration(x, **p), -(K @ x) / m[:, None], rtol=1e-13, atol=1e-13)


def test_chain_derivation_does_not_grow_with_n():
    small = derive(load_scene("ch.toml", text=chain_scene(10, "free", "free"))).source
    large = derive(load_scene("ch.toml", text=chain_scene(1_000_000, "free", "free"))).source
    assert abs(len(small.splitlines()) - len(large.splitlines())) == 0


def test_long_chain_streams_with_bounded_memory(tmp_path):
    n, steps, every = 200_000, 200, 2  # 101 frames: holding them would take 2 x 101 x n x 8 bytes
    scene = load_scene("ch.toml", text=chain_scene(n, "wall", "wall"))
    module, _ = load_module(scene)
    system = System.from_module(module)
    tracemalloc.start()
    summary = stream_methods(system, scene.x0, scene.v0, 0.1, steps, ["verlet"], every, tmp_path, "ch",
                             figures=False)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    frames = steps // every + 1
    # a bounded number of state-sized temporaries (kernel coefficients, energy per frame),
    # never the (frames x n) trajectory, which would need 2 x 101 x n x 8 bytes
    assert peak < 60 * n * 8 < 2 * frames * n * 8
    data = np.load(summary["npz"])
    assert data["x_verlet"].shape == (frames, n)
    assert np.allclose(data["x_verlet"][0], scene.x0)


@pytest.mark.parametrize("ends", [("free", "free"), ("wall", "free"), ("ring", "ring")])
def test_chain_verlet_fused_kernel_equals_plain_verlet(ends):
    """simulate's chain Verlet (fused kernel) is the same scheme as the reference Verlet."""
    from springchain.numeric.run.driver import integrate
    from springchain.numeric.integrators import VelocityVerlet
    from springchain.numeric.integrators.base import Problem
    from springchain.numeric.run.step import FusedChainVerlet

    scene = load_scene("ch.toml", text=chain_scene(257, *ends, mass="m*(1 + i % 2)", k="k*(1 + 0.01*i)"))
    module, _ = load_module(scene)
    system = System.from_module(module)
    problem = Problem(system.acceleration_fn)
    a = integrate(VelocityVerlet(), problem, scene.x0, scene.v0 + 0.01, 0.05, 300, record_every=100)
    b = integrate(FusedChainVerlet(system), problem, scene.x0, scene.v0 + 0.01, 0.05, 300, record_every=100)
    np.testing.assert_allclose(b.x, a.x, rtol=1e-11, atol=1e-14)
    np.testing.assert_allclose(b.v, a.v, rtol=1e-11, atol=1e-14)
