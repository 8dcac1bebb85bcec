"""Damping in [chain] scenes (issue 11, item 6): [[dampers]] families indexed by i, single
dashpots, and [damping] rayleigh, as a dashpot list (stencil, never N x N for long chains).

The reference is assembled here from the TOML text (expressions evaluated with SymPy at each
index) and integrated by DOP853.
"""

from __future__ import annotations

import json
from pathlib import Path

import mpmath
import numpy as np
import pytest
import sympy

import helpers
from helpers import TomlScene, chain_toml, refused_scene, stamp, write_scene
from springchain._modules import derive
from springchain.cli import main
from springchain.derive.scene import load_scene
from springchain.numeric import system as system_mod
from springchain.numeric.run.simulate import run_methods

ROOT = Path(__file__).resolve().parents[2]


DAMPERS = """
[[dampers]]
between = ["i", "i+1"]
c = "c*(1 + 0.2*i)"
[[dampers]]
between = ["i", "wall"]
c = "c/10"
[[dampers]]
between = [2, 6]
c = "c"
"""
RAYLEIGH = '[damping]\nrayleigh = ["a", "b"]'
FORCED = RAYLEIGH + '\n[[forces]]\non = 7\nf = "0.2*cos(1.1*t)"'


def text_of(extra: str, n: int = 8, v: str = "0.01*i", uniform: bool = False) -> str:
    return chain_toml(n, "wall", "free", name="chd", parameters={"m": 1.7, "k": 2.3, "c": 0.05, "a": 0.02, "b": 0.003},
                      mass="m" if uniform else "m*(1 + 0.1*i)", k="k" if uniform else "k*(1 + 0.05*i)",
                      initial={"x": "0.1*sin(pi*(i + 1)/(n + 1))", "v": v}, simulation={"dt": 0.05, "steps": 400},
                      extra=extra)


def reference(text: str):
    """M, K, C (dense, small n) and the right-hand side from the raw TOML."""
    toml = TomlScene(text)
    data, at = toml.data, toml.value
    ch = data["chain"]
    n = ch["n"]
    M = np.diag([at(ch["mass"], i=i) for i in range(n)])
    K = np.zeros((n, n))
    stamp(K, 0, -1, at(ch["k"], i=-1))  # left wall spring (i = -1)
    for i in range(n - 1):
        stamp(K, i, i + 1, at(ch["k"], i=i))
    C = np.zeros((n, n))
    for d in data.get("dampers", []):
        if d["between"] == ["i", "i+1"]:
            for i in range(n - 1):
                stamp(C, i, i + 1, at(d["c"], i=i))
        elif d["between"] == ["i", "wall"]:
            for i in range(n):
                stamp(C, i, -1, at(d["c"], i=i))
        else:
            a, b = (-1 if e == "wall" else e for e in d["between"])
            stamp(C, a, b, at(d["c"], i=0))
    if "damping" in data:
        al, be = (at(e, i=0) for e in data["damping"]["rayleigh"])
        C = C + al * M + be * K
    forces = [(f["on"], toml.of_t(f["f"])) for f in data.get("forces", [])]

    def rhs(t, z):
        x, v = z[:n], z[n:]
        f = -K @ x - C @ v
        for on, fn in forces:
            f[on] += float(fn(t))
        return np.concatenate([v, f / np.diag(M)])

    return M, K, C, rhs


def reference_run(text, x0, v0, t):
    *_, rhs = reference(text)
    return helpers.dop853(rhs, x0.shape[0], x0, v0, t)


def chain_system_of_text(text):
    scene = load_scene("chd.toml", text=text)
    return (scene, *helpers.system_of(scene))


@pytest.mark.parametrize("extra", [DAMPERS, RAYLEIGH, DAMPERS + RAYLEIGH])
def test_chain_damping_matrix_and_stencil_match_reference(extra):
    text = text_of(extra)
    _, module, system = chain_system_of_text(text)
    _, _, C, _ = reference(text)
    got = module.damping_matrix(**system.params)
    assert np.max(np.abs(got - C)) <= 1e-14 * np.max(np.abs(C))
    v = np.random.default_rng(2).standard_normal((8, 3))
    assert np.allclose(module.damping_acceleration(v, **system.params), -(C @ v) / system.masses[:, None],
                       rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("extra", [DAMPERS, DAMPERS + RAYLEIGH, FORCED])
def test_chain_exact_solution_matches_dop853(extra):
    text = text_of(extra)
    scene, _, system = chain_system_of_text(text)
    run = run_methods(system, scene.x0, scene.v0, scene.dt, 400, ["modal"])["modal"]
    xr, vr = reference_run(text, scene.x0, scene.v0, run.t)
    assert np.max(np.abs(run.x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(run.v - vr)) <= 1e-8 * np.max(np.abs(vr))


@pytest.mark.parametrize("sparse", [False, True])
def test_chain_verlet_is_second_order(sparse, monkeypatch):
    """Dense exp(A h/2) half flows (short chains) and the sparse Crank-Nicolson half flows of long
    chains (forced here by lowering the threshold) both converge at order 2."""
    if sparse:
        monkeypatch.setattr(system_mod, "LOADED_CHAIN_EXACT_MAX", 4)
    text = text_of(DAMPERS + FORCED)
    scene, _, system = chain_system_of_text(text)
    import scipy.sparse

    assert scipy.sparse.issparse(system.damping_rate_matrix()) == sparse
    hs = [0.05, 0.025, 0.0125]
    errs = []
    for h in hs:
        run = run_methods(system, scene.x0, scene.v0, h, int(round(10.0 / h)), ["verlet"])["verlet"]
        xr, _ = reference_run(text, scene.x0, scene.v0, run.t)
        errs.append(np.max(np.abs(run.x - xr)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 2.0) < 0.15, (errs, slope)


def test_long_damped_chain_runs_without_dense_matrices():
    text = text_of(DAMPERS + RAYLEIGH, n=5000, v="0")
    scene, module, system = chain_system_of_text(text)
    Ad = system.damping_rate_matrix()
    import scipy.sparse

    assert scipy.sparse.issparse(Ad) and Ad.nnz < 10 * scene.n
    run = run_methods(system, scene.x0, scene.v0, 0.05, 40, ["verlet"])["verlet"]
    E = system.energy(run.x.T, run.v.T)
    assert np.all(np.isfinite(run.x)) and E[-1] < E[0]  # damping removes energy
    with pytest.raises(ValueError):
        module.damping_matrix(**system.params)  # n > MAX_DENSE: refused, never allocated


def test_generated_chain_source_has_damping_only_when_declared():
    plain = derive(load_scene("chd.toml", text=text_of(""))).source
    damped = derive(load_scene("chd.toml", text=text_of(DAMPERS))).source
    ray = derive(load_scene("chd.toml", text=text_of(RAYLEIGH))).source
    for marker in ("damper_ends", "damping_acceleration", "damping_matrix", "rayleigh"):
        assert marker not in plain
    assert "def damper_ends" in damped and "rayleigh" not in damped
    assert "def rayleigh_coefficients" in ray and "def damping_acceleration" in ray
    assert "damper" not in (ROOT / "generated" / "chain100k.py").read_text()


def test_uniform_chain_rayleigh_zeta_family(tmp_path, capsys):
    text = text_of(RAYLEIGH, uniform=True)
    path = tmp_path / "chd.toml"
    path.write_text(text)
    assert main(["modes", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    fam = sympy.sympify(data["damping"]["zeta_family"])
    w2 = sympy.sympify(data["family"]["omega2"])
    vals = {"a": 0.02, "b": 0.003, "k": 2.3, "m": 1.7, "n": 8}
    for j in (1, 4, 8):
        w = float(sympy.sqrt(w2.subs(vals).subs("j", j)))
        assert float(fam.subs(vals).subs("j", j)) == pytest.approx(0.02 / (2 * w) + 0.003 * w / 2, rel=1e-12)


@pytest.mark.parametrize("extra, expect", [
    ("[damping]\nmodal = 0.05", "damping.modal: 0.05: modal damping on a [chain] is not yet supported"),
    ('[[dampers]]\nbetween = [0, 9]\nc = "c"', "dampers[0].between: 9: not a mass index 0 ... 7"),
    ('[[dampers]]\nbetween = ["i", "i+1"]\nc = "c*(1 - 0.2*i)"', "dampers[0].c"),
    ('[[dampers]]\nbetween = [3, 3]\nc = "c"', "both ends are the same"),
    ('[[dampers]]\nbetween = [0, "wall"]\nc = "c*i"', "dampers[0].c"),
])
def test_bad_chain_dampers_are_refused(extra, expect, tmp_path, capsys):
    refused_scene(write_scene(tmp_path, "chd", text_of(extra)), capsys, expect)


@pytest.mark.parametrize("n, left, gamma", [(3, "free", 3.0), (6, "free", 2.5), (6, "wall", 1.2), (9, "free", 4.0)])
def test_proportional_overdamped_chain_zeta_is_gamma_over_two_omega(n, left, gamma, tmp_path, capsys):
    """C = γM (a dashpot γ m_i from every mass to the ground): ζ_j = γ/(2ω_j) for every elastic mode, above 1
    for the overdamped ones (oracle finding N15: real eigenvalues of different modes were paired by value)."""
    text = chain_toml(n, left, "free", name="odc", parameters={"m": 1.3, "k": 2.0, "c": gamma},
                      mass="m*(1 + 0.1*i)", k="k*(1 + 0.05*i)",
                      extra='[[dampers]]\nbetween = ["i", "wall"]\nc = "c*m*(1 + 0.1*i)"\n')
    path = tmp_path / "odc.toml"
    path.write_text(text)
    assert main(["modes", str(path), "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["modes"]
    # the reference: ω_j from the mass and stiffness matrices assembled here, at 30 digits
    m = [1.3 * (1 + 0.1 * i) for i in range(n)]
    K = np.zeros((n, n))
    for i in range(n - 1):
        stamp(K, i, i + 1, 2.0 * (1 + 0.05 * i))
    if left == "wall":
        stamp(K, -1, 0, 2.0 * (1 + 0.05 * -1))
    with mpmath.workdps(30):
        r = [1 / mpmath.sqrt(mpmath.mpf(v)) for v in m]
        D = mpmath.matrix([[r[a] * K[a, b] * r[b] for b in range(n)] for a in range(n)])
        w2 = sorted(float(v) for v in mpmath.eigsy(D, eigvals_only=True))
    assert len(modes) == n
    over = 0
    for row, ref in zip(sorted(modes, key=lambda r: r["omega2_value"]), w2):
        if abs(ref) < 1e-12:
            assert row["damping_ratio"] is None
            continue
        zeta = gamma / (2 * np.sqrt(ref))
        over += zeta > 1
        assert row["damping_ratio"] == pytest.approx(zeta, rel=1e-10), (ref, row)
    assert over >= 1
