"""Spring potentials (issue 21), the numeric side: the compiled law kernels, energy over 10⁶ steps,
convergence orders and `plan`'s predictions against an exact Toda soliton, modal energies and the
FPUT recurrence.

The exact solution is derived here, not taken from springchain: the Toda lattice
``m x_i'' = a (e^{-b r_{i-1}} - e^{-b r_i})``, ``r_i = x_{i+1} - x_i`` carries the soliton
``e^{-b r_i} - 1 = sinh²κ sech²(κ(i - c) - βt)``, ``β = √(ab/m) sinh κ``, i.e.
``x_i(t) = (1/b) [log(1 + e^{2(κ(i-1-c) - βt)}) - log(1 + e^{2(κ(i-c) - βt)})]`` (checked below by
substituting it into the equations of motion with SymPy).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp


def toda_text(n=64, c=24.0, kappa=1.0, steps=80, dt=0.05, record_every=1, left="free", right="free"):
    return f"""name = "toda_t"
[parameters]
m = 1.0
a = 1.0
b = 1.0
kappa = {kappa!r}
c = {c!r}
[chain]
n = {n}
mass = "m"
potential = "a/b*exp(-b*d) + a*d"
left = "{left}"
right = "{right}"
[initial]
x = "log((1 + exp(2*kappa*(i - 1 - c)))/(1 + exp(2*kappa*(i - c))))/b"
v = "sqrt(a*b/m)*sinh(kappa)*(tanh(kappa*(i - c)) - tanh(kappa*(i - 1 - c)))/b"
[simulation]
dt = {dt!r}
steps = {steps}
record_every = {record_every}
"""


def soliton(t, n, c, kappa=1.0, a=1.0, b=1.0, m=1.0):
    """x_i(t) of the Toda soliton, shape (S, n) (logaddexp: no overflow far from the centre)."""
    beta = math.sqrt(a * b / m) * math.sinh(kappa)
    i = np.arange(n, dtype=float)[None, :]
    z = kappa * (i - c) - beta * np.asarray(t, dtype=float)[:, None]
    return (np.logaddexp(0.0, 2 * (z - kappa)) - np.logaddexp(0.0, 2 * z)) / b


def test_soliton_solves_the_toda_equations():
    """The formula above satisfies the lattice equations identically (SymPy, at symbolic i and t)."""
    i, t, kappa = sp.symbols("i t kappa", real=True)
    beta = sp.sinh(kappa)  # a = b = m = 1

    def x(j):
        return sp.log((1 + sp.exp(2 * (kappa * (j - 1) - beta * t))) / (1 + sp.exp(2 * (kappa * j - beta * t))))

    lhs = sp.diff(x(i), t, 2)
    rhs = sp.exp(-(x(i) - x(i - 1))) - sp.exp(-(x(i + 1) - x(i)))
    R = sp.Rational
    for iv, tv, kv in ((R(3, 10), R(7, 10), 1), (-2, R(3, 2), R(1, 2)), (4, -1, R(13, 10))):
        val = (lhs - rhs).subs({i: iv, t: tv, kappa: kv}).evalf(40)
        assert abs(val) < 1e-30


# -- the compiled law kernels against the module's NumPy stencil ------------------------------------------
#: The Toda and FPUT-α laws with the bundled scenes' parameter names (c, kappa unused by the law): their
#: generated spring_force is the bundled one's, so each law's compiled kernels are compiled once per run.
LAWS = {"toda": ("a/b*exp(-b*d) + a*d", {"a": 1.0, "b": 1.3, "c": 32.0, "kappa": 1.0}),
        "fput_a": ("k*d**2/2 + alpha*d**3/3", {"k": 1.0, "alpha": 0.7})}  # the bundled fput_alpha's law text


def chain_module(scene_from_text, import_source, name, pot, params, n, left, right):
    from springchain._modules import derive

    p = "\n".join(f"{k} = {v!r}" for k, v in {"m": 1.0, **params}.items())
    text = f'name = "{name}"\n[parameters]\n{p}\n[chain]\nn = {n}\nmass = "m"\npotential = "{pot}"\n' \
           f'left = "{left}"\nright = "{right}"\n'
    return import_source(derive(scene_from_text(text, f"{name}.toml")).source, name)


@pytest.mark.parametrize("law", sorted(LAWS))
def test_law_kernel_equals_numpy_stencil(law, scene_from_text, import_source, monkeypatch):
    from springchain.numeric.compiled import fast as fast_module
    from springchain.numeric.compiled.fast import Backend, FusedVerlet, available
    from springchain.numeric.system import System

    monkeypatch.setattr(fast_module, "COMPILED_FORCE_MIN_N", 1)  # the other step methods' force, at n = 9

    if not available():
        pytest.skip("numba is not installed")
    pot, params = LAWS[law]
    rng = np.random.default_rng(5)
    for left, right in (("wall", "wall"), ("free", "free"), ("wall", "free"), ("ring", "ring")):
        mod = chain_module(scene_from_text, import_source, f"k_{law}_{left}", pot, params, 9, left, right)
        for shape in ((9,), (9, 3)):
            x = 0.3 * rng.standard_normal(shape)
            v = 0.3 * rng.standard_normal(shape)
            fused = FusedVerlet.from_module(mod, None, 9, 0.05, Backend.NUMBA)
            plain = FusedVerlet.from_module(mod, None, 9, 0.05, Backend.NUMPY)
            assert fused.coefficients.law is not None
            a1, a2 = fused.force(x.copy()), plain.force(x.copy())
            assert np.allclose(a1, a2, rtol=1e-14, atol=1e-15 * np.max(np.abs(a2)))
            a3 = fast_module.compiled_acceleration(System.from_module(mod, None, n=9))(x.T.copy().T)  # not contiguous
            assert np.allclose(a3, a2, rtol=1e-14, atol=1e-15 * np.max(np.abs(a2)))
            s1 = [x.copy(), v.copy(), a1.copy()]
            s2 = [x.copy(), v.copy(), a2.copy()]
            fused.advance(*s1, 101)
            plain.advance(*s2, 101)
            assert np.max(np.abs(s1[0] - s2[0])) <= 1e-12 * np.max(np.abs(s2[0])), (law, left, shape)
            xs, vs, as_ = fused.step(x.copy(), v.copy(), a1.copy())
            xp, vp, ap = plain.step(x.copy(), v.copy(), a2.copy())
            assert np.allclose(xs, xp, rtol=1e-14, atol=1e-15) and np.allclose(vs, vp, rtol=1e-13, atol=1e-15)


def test_law_kernels_are_cached_on_disk_once_per_law():
    """A spring potential's kernels live in a file of their own (``<cache>/compiled/law_<hash>.py``) with
    the law bound inside: a second process loads them from numba's disk cache and compiles nothing, and
    another parameter set of the same law uses the same file (the values are run-time arguments)."""
    from springchain.numeric.compiled import fast_kernels

    if not fast_kernels.available():
        pytest.skip("numba is not installed")
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}  # the run's cache: the first child may find the law there
    runs = [json.loads(subprocess.run([sys.executable, "-c", _LAW_CHILD], env=env, capture_output=True,
                                      text=True, check=True).stdout.strip().splitlines()[-1]) for _ in range(2)]
    assert runs[1]["misses"] == 0 and runs[1]["hits"] > 0, runs[1]
    assert len({path for r in runs for path in r["paths"]}) == 1  # one file: both runs, both parameter sets
    assert runs[0]["x"] == runs[1]["x"]
    assert runs[0]["x"] != runs[0]["x_other"]  # the second parameter set is a different motion


_LAW_CHILD = """
import json
import numpy as np
from springchain.numeric.compiled.fast import Backend, FusedVerlet
from springchain._modules import load_module
from springchain._scenes import resolve
from springchain.derive.scene import load_scene

module, _ = load_module(load_scene(resolve("toda")))
x = 0.1 * np.sin(np.arange(module.N, dtype=float))
runs, paths = [], []
for params in (None, {"a": 2.0}):
    fused = FusedVerlet.from_module(module, params, module.N, 0.05, Backend.NUMBA)
    s = [x.copy(), np.zeros_like(x), fused.force(x.copy())]
    fused.advance(*s, 50)
    runs.append(float(s[0].sum()))
    paths.append(fused.coefficients.law.path)
k = fused.coefficients.law.kernels
stats = [d.stats for d in (k.force, k.sweep, k.half_kick)]
print(json.dumps({"misses": sum(sum(s.cache_misses.values()) for s in stats),
                  "hits": sum(sum(s.cache_hits.values()) for s in stats),
                  "paths": paths, "x": runs[0], "x_other": runs[1]}))
"""


def test_energy_bounded_over_a_million_steps(scene_from_text, import_source):
    """Verlet (the fused law kernel) on an FPUT-α chain of 8 masses: 10⁶ steps, energy error bounded
    at the h² level and not growing (the last tenth's largest error within 1.5 x the first tenth's)."""
    from springchain.numeric.compiled.fast import Backend, FusedVerlet, available

    pot, params = LAWS["fput_a"]
    mod = chain_module(scene_from_text, import_source, "e_fput_a", pot, params, 8, "wall", "wall")
    backend = Backend.NUMBA if available() else Backend.NUMPY
    h = 0.1
    fv = FusedVerlet.from_module(mod, None, 8, h, backend)
    x = 0.8 * np.sin(np.pi * np.arange(1, 9) / 9)
    v = np.zeros(8)
    a = fv.force(x.copy())
    e0 = float(mod.energy(x, v, **mod.DEFAULTS))
    chunks, per = 100, 10_000
    errs = np.empty(chunks)
    for c in range(chunks):
        fv.advance(x, v, a, per)
        errs[c] = abs(float(mod.energy(x, v, **mod.DEFAULTS)) - e0) / e0
    assert np.all(np.isfinite(errs)) and errs.max() <= 5e-3  # (ω_max h)² / 8 ≈ 0.02 times the energy, at most
    assert errs[-10:].max() <= 1.5 * errs[:10].max() + 1e-12


@pytest.mark.parametrize("method", ["yoshida4", "blanes-moan4"])
def test_higher_order_symplectic_energy_bounded(method, tmp_path):
    """Through the run layer (the NumPy stencil): 1.5·10⁴ steps of a soliton between walls, bouncing
    (about 25 crossings); energy error at the (ωh)⁴ level and not growing."""
    import springchain as sc
    from springchain._modules import load_module

    path = tmp_path / "toda_t.toml"
    path.write_text(toda_text(n=32, c=8.0, steps=15_000, dt=0.05, record_every=150, left="wall", right="wall"))
    run = sc.simulate(path, methods=[method], out=tmp_path, progress=False)
    mod, _ = load_module(sc.load(path))
    e = mod.energy(run.x[method].T, run.v[method].T, **mod.DEFAULTS)
    errs = np.abs(e - e[0]) / e[0]
    assert errs.max() <= 1e-4, errs.max()
    assert errs[-10:].max() <= 1.5 * errs[:10].max() + 1e-13


# -- convergence orders and plan, against the exact soliton ------------------------------------------------
STEPS = {2: (0.1, 0.05, 0.025), 4: (0.2, 0.1, 0.05), 6: (0.25, 0.125, 0.0625), 8: (0.25, 0.125, 0.0625)}


@pytest.mark.parametrize("method", ["verlet", "yoshida4", "blanes-moan4", "blanes-moan6", "rk4"])
def test_convergence_slope_matches_declared_order(method, tmp_path):
    import springchain as sc
    from springchain.numeric.run import registry

    order = registry.method(method).traits.order
    t_end, n, c = 4.0, 64, 24.0
    errs = []
    hs = STEPS[order]
    for h in hs:
        steps = round(t_end / h)
        path = tmp_path / "toda_t.toml"
        path.write_text(toda_text(n=n, c=c, steps=steps, dt=h, record_every=steps // 4))
        run = sc.simulate(path, methods=[method], out=tmp_path, progress=False)
        exact = soliton(run.t, n, c)
        errs.append(float(np.max(np.abs(run.x[method] - exact))))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - order) <= 0.3, (method, errs, slope)


def test_plan_predicts_the_soliton_error(tmp_path):
    """plan's predicted error (pilot-calibrated against DOP853) holds against the exact soliton."""
    import springchain as sc

    t_end, n, c, tol = 8.0, 64, 24.0, 1e-5
    path = tmp_path / "toda_t.toml"
    path.write_text(toda_text(n=n, c=c, steps=160, dt=0.05))
    p = sc.plan(path, tol=tol, t_end=t_end)
    checked = 0
    for cand in p.candidates:
        name = cand.method.name
        if name not in ("verlet", "yoshida4", "blanes-moan6", "kahan-li8", "dop853", "dprkn8"):
            continue
        if cand.rtol is not None:
            from springchain.numeric.plan.planner import adaptive_atol

            scene = sc.load(path)
            run = sc.simulate(path, methods=[name], dt=t_end / 160, steps=160, out=tmp_path, progress=False,
                              rtol=cand.rtol, atol=adaptive_atol(scene.x0, scene.v0, cand.rtol))
        else:
            run = sc.simulate(path, methods=[name], dt=cand.dt, steps=cand.steps, out=tmp_path, progress=False)
        err = float(np.max(np.abs(run.x[name] - soliton(run.t, n, c))))
        assert err <= tol, (name, err, cand.predicted_error)
        checked += 1
    assert checked >= 4


# -- modal energies ---------------------------------------------------------------------------------
@pytest.mark.parametrize("ends", [("free", "free"), ("wall", "wall"), ("wall", "free"), ("free", "wall"),
                                  ("ring", "ring")])
@pytest.mark.parametrize("n", [7, 8])
def test_modal_energy_transform_equals_eigenvectors(ends, n, scene_from_text, import_source):
    from springchain._modules import derive
    from springchain.numeric.exact.chain import Basis
    from springchain.numeric.exact.modal_energy import ModalEnergy
    from springchain.numeric.modes.spectrum import spectrum
    from springchain.numeric.system import System

    left, right = ends
    text = (f'name = "me"\n[parameters]\nm = 2.0\nk = 3.0\n[chain]\nn = {n}\nmass = "m"\nk = "k"\n'
            f'left = "{left}"\nright = "{right}"\n')
    mod = import_source(derive(scene_from_text(text, "me.toml")).source, "me")
    system = System.from_module(mod)
    fast = ModalEnergy.from_system(system)
    assert fast.basis is not Basis.EIGENVECTORS
    spec = spectrum(system.masses, system.spring_ends, system.stiffness)
    dense = ModalEnergy(spec.omega, np.zeros(n), Basis.EIGENVECTORS, np.sqrt(system.masses), np.arange(n), spec.vectors)
    rng = np.random.default_rng(n)
    x, v = rng.standard_normal((2, 5, n))
    e_fast, e_dense = fast.energies(x, v), dense.energies(x, v)
    assert np.allclose(fast.omega, spec.omega, rtol=1e-14, atol=1e-15)
    total = system.energy(x.T, v.T)
    assert np.allclose(e_fast.sum(axis=1), total, rtol=1e-13)
    if left != "ring":  # a ring's repeated pairs may mix: compare their sums
        assert np.allclose(e_fast, e_dense, rtol=1e-12, atol=1e-14 * total.max())


def test_modal_energy_constant_under_the_exact_linear_solution(tmp_path):
    import springchain as sc

    text = ('name = "lin"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 16\nmass = "m"\nk = "k"\nleft = "wall"\n'
            'right = "free"\n[initial]\nx = "0.1*sin(i) + 0.02*i"\nv = "0.05*cos(3*i)"\n[simulation]\ndt = 0.3\n'
            'steps = 300\nrecord_every = 10\n')
    path = tmp_path / "lin.toml"
    path.write_text(text)
    run = sc.simulate(path, methods=["modal"], out=tmp_path, progress=False, modal_energy=True)
    e = run.extra["modal_energy_modal"]
    assert e.shape == (31, 16)
    assert np.max(np.abs(e - e[0])) <= 1e-12 * e.sum(axis=1).max()


def test_modal_energy_about_the_sag_of_a_linear_scene(tmp_path):
    """hanging (gravity from a wall): modes about x_eq = K⁻¹Mg (numeric.exact.equilibrium); under the exact
    solution every E_j is constant."""
    import springchain as sc

    run = sc.simulate("hanging", methods=["modal"], out=tmp_path, progress=False, modal_energy=True)
    e = run.extra["modal_energy_modal"]
    assert np.max(np.abs(e - e[0])) <= 1e-11 * e.sum(axis=1).max()


def test_fput_recurrence(tmp_path):
    """The bundled fput_alpha scene: all energy in mode 1 at t = 0, most of it gone by t ≈ 3000,
    back (≥ 95 %) near t ≈ 10⁴ — the FPUT recurrence (Verlet at the scene's dt = 0.1)."""
    import springchain as sc

    run = sc.simulate("fput_alpha", methods=["verlet"], out=tmp_path, progress=False, modal_energy=True)
    e = run.extra["modal_energy_verlet"]
    total = e.sum(axis=1)
    share = e[:, 0] / total
    t = run.t
    assert share[0] >= 0.999
    assert share[(t > 2000) & (t < 6000)].min() <= 0.15
    assert share[(t > 9000) & (t < 11000)].max() >= 0.95
    # the harmonic sum misses only the cubic part of V (α d³/3): a few per cent of E here
    assert np.max(np.abs(total - total[0])) <= 0.05 * total[0]
    assert (tmp_path / "fput_alpha.npz").exists()
    data = np.load(tmp_path / "fput_alpha.npz")
    assert data["modal_energy_verlet"].shape == e.shape


def test_simulate_cli_modal_energy(tmp_path, capsys):
    from springchain.cli import main

    status = main(["simulate", "toda", "--modal-energy", "--steps", "40", "--record-every", "10", "--out",
                   str(tmp_path)])
    out, _ = capsys.readouterr()
    assert status == 0
    assert (tmp_path / "toda-modal-energy.png").exists()
    data = np.load(tmp_path / "toda.npz")
    assert data["modal_energy_verlet"].shape == (5, 128)


def test_a_tension_that_calls_a_helper_compiles_with_its_scalar_form(import_source):
    """A tension that calls ``_expm1mx`` (array form in the module) runs in the law file through the
    scalar form the module carries: the compiled force equals the NumPy formula on a free chain."""
    from springchain.derive.law_helpers import helper_source
    from springchain.generated.contract import End, Layout, Provided
    from springchain.numeric.compiled.fast_kernels import available
    from springchain.numeric.compiled.potential_law import compiled_law
    from springchain.numeric.system import System

    if not available():
        pytest.skip("numba is not installed")
    src = ("import numpy as _np\nSCENE = 'helper_law'\nPARAMETERS = ('a',)\n\n\n"
           "def spring_force(_d, a):\n    return a * _d + _expm1mx(_d)\n\n\n"
           + helper_source({"_expm1mx", "_expm1mx_s"}))
    mod = import_source(src, "helper_law")
    # a module that binds the law only: the System around it states the rest of the contract by hand
    facts = Provided(scene="helper_law", scene_sha256="", parameters=("a",), defaults={"a": 2.0}, n=5,
                     effects=frozenset({"spring"}), linear=False, layout=Layout.CHAIN, rigid_modes=1)
    law = compiled_law(System(mod, {"a": 2.0}, np.ones(5), np.zeros((0, 2), dtype=np.intp), np.zeros(0),
                              provided=facts))
    x = np.array([0.3, -0.2, 0.9, 0.1, -0.7])
    a = np.empty_like(x)
    free = End.FREE.code
    law.kernels.force(x, a, 1, 5, 1.0, 0.0, law.args, 0.0, 0.0, law.args, law.args, free, free)
    t = mod.spring_force(np.diff(x), 2.0)
    expected = np.concatenate([[0.0], t]) * -1 + np.concatenate([t, [0.0]])
    assert np.allclose(a, expected, rtol=1e-14, atol=1e-16)
