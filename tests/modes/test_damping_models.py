"""[damping] models (issue 11, item 3): Rayleigh C = αM + βK and modal ratios ζⱼ.

References are built here from the TOML text only (tomllib + SymPy for the numbers, SciPy for
the modes of the modal reference) and integrated by solve_ivp DOP853 at rtol 1e-12.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import sympy

import helpers
from helpers import WALL_THREE, TomlScene, refused_scene, scene_toml, write_scene
from springchain._modules import derive, load_module
from springchain.cli import main
from springchain.derive.model import Model
from springchain.derive.scene import load_scene
from springchain.numeric.run.simulate import run_methods
from springchain.numeric.system import System

ROOT = Path(__file__).resolve().parents[2]


RAYLEIGH = '[damping]\nrayleigh = ["a", "b"]'
MODAL = '[damping]\nmodal = [0.02, "a", 0.1]'
MODAL_ONE = "[damping]\nmodal = 0.03"
RAYLEIGH_DASHPOT = RAYLEIGH + '\n[[dampers]]\nbetween = ["m3", "wall"]\nc = "c"'
MODAL_DASHPOT = MODAL + '\n[[dampers]]\nbetween = ["m1", "m2"]\nc = "c"'
FORCED_RAYLEIGH = RAYLEIGH + '\n[[forces]]\non = "m3"\nf = "0.4*cos(1.3*t) + 0.1"'


def three_mass_text(extra: str) -> str:
    return scene_toml("dm", {"m": 2.0, "k": 3.0, "a": 0.05, "b": 0.01, "c": 0.3}, **WALL_THREE, extra=extra,
                      initial={"x": [0.1, 0.0, -0.1], "v": [0.0, 0.2, 0.0]}, simulation={"dt": 0.05, "steps": 400})


# -- an independent reference from the TOML text ------------------------------------------------
def reference_matrices(text: str):
    """M, K, C and a force function from the raw TOML (no springchain code)."""
    toml = TomlScene(text)
    data, num = toml.data, toml.value
    idx = toml.mass_index()
    _, M, K, C = toml.matrices()
    n = M.shape[0]
    damping = data.get("damping", {})
    if "rayleigh" in damping:
        alpha, beta = (num(e) for e in damping["rayleigh"])
        C = C + alpha * M + beta * K
    if "modal" in damping:
        z = damping["modal"]
        zeta = np.array([num(e) for e in z]) if isinstance(z, list) else np.full(n, num(z))
        w2, Phi = scipy.linalg.eigh(K, M)  # independent of springchain's spectrum route
        MP = M @ Phi
        C = C + MP @ np.diag(2 * zeta * np.sqrt(np.maximum(w2, 0))) @ MP.T
    forces = [(idx[f["on"]], toml.of_t(f["f"])) for f in data.get("forces", [])]

    def force(tt):
        out = np.zeros(n)
        for on, fn in forces:
            out[on] += float(fn(tt))
        return out

    return M, K, C, force


def reference_run(text, x0, v0, t):
    M, K, C, force = reference_matrices(text)
    n = M.shape[0]
    minv = 1 / np.diag(M)

    def rhs(tt, z):
        x, v = z[:n], z[n:]
        return np.concatenate([v, minv * (force(tt) - K @ x - C @ v)])

    return helpers.dop853(rhs, n, x0, v0, t)


def system_of_text(text: str):
    scene = load_scene("dm.toml", text=text)
    return scene, helpers.system_of(scene)[1]


# -- derivation ----------------------------------------------------------------------------------
def test_rayleigh_damping_matrix_is_alpha_m_plus_beta_k_exactly():
    model = Model(load_scene("dm.toml", text=three_mass_text(RAYLEIGH_DASHPOT)))
    a, b, c, k, m = (model.params[s] for s in ("a", "b", "c", "k", "m"))
    M = sympy.diag(m, 2 * m, m)
    K = sympy.Matrix([[2 * k, -k, 0], [-k, 3 * k, -2 * k], [0, -2 * k, 2 * k]])
    dashpot = sympy.diag(0, 0, c)
    assert (model.C - (a * M + b * K + dashpot)).applyfunc(sympy.expand) == sympy.zeros(3, 3)
    # the Rayleigh dissipation function gives the same C and the same equations of motion
    R = model.R
    assert sympy.Matrix(3, 3, lambda i, j: sympy.diff(R, model.v[i], model.v[j])) == model.C
    el = model.euler_lagrange()
    x, v, acc = sympy.Matrix(model.x), sympy.Matrix(model.v), sympy.Matrix(model.a)
    assert (sympy.Matrix(el) - (M * acc + model.C * v + K * x)).applyfunc(sympy.expand) == sympy.zeros(3, 1)


@pytest.mark.parametrize("extra", [RAYLEIGH, MODAL, MODAL_ONE, RAYLEIGH_DASHPOT, MODAL_DASHPOT])
def test_generated_damping_matrix_matches_reference(extra):
    text = three_mass_text(extra)
    _, system = system_of_text(text)
    _, _, C_ref, _ = reference_matrices(text)
    C = np.asarray(system.module.damping_matrix(**system.params))
    assert np.allclose(C, C.T, rtol=0, atol=0)
    assert np.max(np.abs(C - C_ref)) <= 1e-12 * np.max(np.abs(C_ref))
    # damping_acceleration agrees with -M^-1 C v on a batch
    vb = np.random.default_rng(3).standard_normal((3, 5))
    got = system.module.damping_acceleration(vb, **system.params)
    assert np.allclose(got, -(C_ref @ vb) / system.masses[:, None], rtol=1e-12, atol=1e-14)


# -- generated source: only declared effects -------------------------------------------------------
def test_adding_rayleigh_or_modal_adds_only_damping_code():
    plain = derive(load_scene("dm.toml", text=three_mass_text(""))).source
    ray = derive(load_scene("dm.toml", text=three_mass_text(RAYLEIGH))).source
    modal = derive(load_scene("dm.toml", text=three_mass_text(MODAL))).source
    for marker in ("damping_matrix", "damping_acceleration", "rayleigh", "modal_damping", "DAMPER_ENDS"):
        assert marker not in plain
    assert "def rayleigh_coefficients" in ray and "def damping_matrix" in ray
    assert "modal_damping" not in ray and "DAMPER_ENDS" not in ray
    assert ("_accurate_modes" in ray) == ("_accurate_modes" in plain)  # only the modes' own use
    assert "def modal_damping_ratios" in modal and "def _modal_damping_matrix" in modal
    assert "rayleigh" not in modal and "DAMPER_ENDS" not in modal
    assert "'rayleigh'" in ray.split("EFFECTS = ", 1)[1].split("\n", 1)[0]
    assert "'modal_damping'" in modal.split("EFFECTS = ", 1)[1].split("\n", 1)[0]


# -- simulation against DOP853 ---------------------------------------------------------------------
@pytest.mark.parametrize("extra", [RAYLEIGH, MODAL, MODAL_DASHPOT, FORCED_RAYLEIGH])
def test_exact_solution_matches_dop853(extra):
    text = three_mass_text(extra)
    scene, system = system_of_text(text)
    run = run_methods(system, scene.x0, scene.v0, scene.dt, 400, ["modal"])["modal"]
    xr, vr = reference_run(text, scene.x0, scene.v0, run.t)
    assert np.max(np.abs(run.x - xr)) <= 1e-8 * np.max(np.abs(xr))
    assert np.max(np.abs(run.v - vr)) <= 1e-8 * np.max(np.abs(vr))


@pytest.mark.parametrize("extra", [RAYLEIGH, MODAL, FORCED_RAYLEIGH])
def test_verlet_converges_at_order_two(extra):
    text = three_mass_text(extra)
    scene, system = system_of_text(text)
    T = 10.0
    hs = [0.05, 0.025, 0.0125]
    errs = []
    for h in hs:
        run = run_methods(system, scene.x0, scene.v0, h, int(round(T / h)), ["verlet"])["verlet"]
        xr, _ = reference_run(text, scene.x0, scene.v0, run.t)
        errs.append(np.max(np.abs(run.x - xr)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 2.0) < 0.15, (errs, slope)


@pytest.mark.parametrize("method", ["yoshida4", "rk4", "blanes-moan6", "dop853", "lsoda"])
def test_other_methods_handle_modal_damping(method):
    text = three_mass_text(MODAL_DASHPOT)
    scene, system = system_of_text(text)
    run = run_methods(system, scene.x0, scene.v0, 0.01, 500, [method])[method]
    xr, _ = reference_run(text, scene.x0, scene.v0, run.t)
    assert np.max(np.abs(run.x - xr)) <= 1e-4 * np.max(np.abs(xr))


def test_bundled_building_rayleigh_exact_matches_dop853():
    path = ROOT / "scenes" / "building_rayleigh.toml"
    text = path.read_text()
    scene = load_scene(path)
    module, _ = load_module(scene)
    system = System.from_module(module)
    x0 = np.array([0.01, -0.02, 0.03])
    run = run_methods(system, x0, np.zeros(3), scene.dt, 800, ["modal"])["modal"]
    xr, _ = reference_run(text, x0, np.zeros(3), run.t)
    assert np.max(np.abs(run.x - xr)) <= 1e-8 * np.max(np.abs(xr))


# -- zeta as printed -------------------------------------------------------------------------------
def modes_json(text: str, tmp_path, capsys) -> dict:
    path = tmp_path / "dm.toml"
    path.write_text(text)
    assert main(["modes", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_rayleigh_zeta_closed_form_and_value(tmp_path, capsys):
    text = three_mass_text(RAYLEIGH)
    data = modes_json(text, tmp_path, capsys)
    M, K, _, _ = reference_matrices(text)
    w = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True))
    a, b = 0.05, 0.01
    expected = a / (2 * w) + b * w / 2
    got = np.array([r["damping_ratio"] for r in data["modes"]])
    assert np.allclose(got, expected, rtol=1e-13)
    assert data["damping"] == {"model": "rayleigh", "proportional": True}
    assert "complex_modes" not in data
    for rec, wj in zip(data["modes"], w):
        expr = sympy.sympify(rec["damping_ratio_expr"])
        assert expr.free_symbols == {sympy.Symbol(s) for s in ("a", "b", "k", "m")}
        value = float(expr.subs({"a": a, "b": b, "k": 3.0, "m": 2.0}))
        assert value == pytest.approx(a / (2 * wj) + b * wj / 2, rel=1e-13)
        assert rec["omega_damped"] == pytest.approx(wj * np.sqrt(1 - (a / (2 * wj) + b * wj / 2) ** 2), rel=1e-13)


PRESTRESSED = """name = "ray7"
[parameters]
m = 1.0
k = 4.0
T = 0.01
c = CUBIC
[masses]
a = "m"
p = "m"
q = "m"
[[springs]]
between = ["wall", "a"]
k = "k"
[[springs]]
between = ["a", "p"]
potential = "T*d + k*d**2/2 + c*d**4/4"
[damping]
rayleigh = ["0.1", "0.01"]
"""


@pytest.mark.parametrize("cubic", ["0.0", "30.0"])
def test_rayleigh_on_a_prestressed_potential_is_proportional(tmp_path, capsys, cubic):
    """Oracle N9: C = αM + βK is proportional by construction, also when a pre-stressed potential moves x_eq
    (K there holds an equilibrium stiffness: with c = 30 not a round number). Reference by hand in mpmath:
    T + k d + c d³ = 0 for the spring a–p (p carries no other spring), k_eq = k + 3 c d², the modes of
    K = [[k + k_eq, −k_eq, 0], [−k_eq, k_eq, 0], [0, 0, 0]] (M = I; q is free), ζ = α/(2ω) + βω/2."""
    import mpmath

    data = modes_json(PRESTRESSED.replace("CUBIC", cubic), tmp_path, capsys)
    assert data["damping"] == {"model": "rayleigh", "proportional": True}
    assert "complex_modes" not in data
    with mpmath.workdps(50):
        c = mpmath.mpf(cubic)
        d = mpmath.findroot(lambda d: mpmath.mpf("0.01") + 4 * d + c * d**3, 0)
        ke = 4 + 3 * c * d**2
        w2 = sorted(mpmath.eigsy(mpmath.matrix([[4 + ke, -ke, 0], [-ke, ke, 0], [0, 0, 0]]), eigvals_only=True))
        zeta = [None] + [mpmath.mpf("0.1") / (2 * mpmath.sqrt(w)) + mpmath.mpf("0.01") * mpmath.sqrt(w) / 2
                         for w in w2[1:]]
    assert data["equilibrium"]["x_value"] == pytest.approx([0.0, float(d), 0.0], rel=1e-14, abs=1e-300)
    got = [r["damping_ratio"] for r in data["modes"]]
    assert got[0] is None  # the free mass q: a rigid mode
    assert got[1:] == pytest.approx([float(z) for z in zeta[1:]], rel=1e-14)


def test_modal_zeta_is_reported_as_given(tmp_path, capsys):
    data = modes_json(three_mass_text(MODAL), tmp_path, capsys)
    assert [r["damping_ratio"] for r in data["modes"]] == pytest.approx([0.02, 0.05, 0.1], rel=1e-15)
    assert [r["damping_ratio_expr"] for r in data["modes"]] == ["1/50", "a", "1/10"]


def test_proportional_dashpots_get_a_closed_form(tmp_path, capsys):
    """Dashpots c = (c/k)·k in parallel with every spring: C = (c/k) K, ζⱼ = c ωⱼ/(2k)·(k/k)."""
    extra = "\n".join(f'[[dampers]]\nbetween = {b}\nc = "{c}"' for b, c in
                      ((["wall", "m1"], "c"), (["m1", "m2"], "c"), (["m2", "m3"], "2*c")))
    text = three_mass_text(extra)
    data = modes_json(text, tmp_path, capsys)
    M, K, C, _ = reference_matrices(text)
    w = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True))
    assert data["damping"]["proportional"] is True
    assert [r["damping_ratio"] for r in data["modes"]] == pytest.approx(0.3 / 3.0 * w / 2, rel=1e-13)
    assert all(r["damping_ratio_expr"] is not None for r in data["modes"])


def test_non_proportional_damping_reports_complex_modes(tmp_path, capsys):
    text = three_mass_text(MODAL_DASHPOT)
    data = modes_json(text, tmp_path, capsys)
    M, K, C, _ = reference_matrices(text)
    n = 3
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    upper = np.sort_complex(lam[lam.imag > 0])
    got = np.array([complex(*c["eigenvalue"]) for c in data["complex_modes"]])
    assert data["damping"] == {"model": "dashpots + modal", "proportional": False}
    assert np.allclose(np.sort_complex(got), upper, rtol=1e-11)
    for c in data["complex_modes"]:
        assert c["sigma"] == pytest.approx(-c["eigenvalue"][0], rel=1e-15)
        assert c["omega_damped"] == pytest.approx(c["eigenvalue"][1], rel=1e-15)
    # the existing fields keep their meaning: ζ = σ/|λ|, ω_d = Im λ
    zeta = [r["damping_ratio"] for r in data["modes"]]
    assert zeta == pytest.approx([-l.real / abs(l) for l in sorted(upper, key=abs)], rel=1e-11)


def test_text_and_latex_show_zeta(tmp_path, capsys):
    path = tmp_path / "dm.toml"
    path.write_text(three_mass_text(RAYLEIGH))
    assert main(["modes", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Damped modes at the scene's values (rayleigh; proportional: real modes)" in out
    assert "zeta = a*sqrt(m)" in out or "zeta = a/" in out
    assert main(["modes", str(path), "--latex"]) == 0
    assert r"\zeta_{1}" in capsys.readouterr().out


# -- hostile input ---------------------------------------------------------------------------------
@pytest.mark.parametrize("extra, expect", [
    ("[damping]\nmodal = -0.1", "damping.modal: -0.1: evaluates to -0.1"),
    ("[damping]\nmodal = nan", "damping.modal: nan"),
    ("[damping]\nmodal = [0.1, 0.2]", "damping.modal: [0.1, 0.2]: 2 ratios for 3 modes"),
    ('[damping]\nmodal = 0.1\nrayleigh = [0.1, 0.2]', "give exactly one damping model"),
    ("[damping]\nrayleigh = [0.1]", "damping.rayleigh: [0.1]: not a list of two coefficients"),
    ('[damping]\nrayleigh = ["a", "-b"]', "damping.rayleigh[1]"),
    ('[damping]\nrayleigh = ["a", "__import__"]', "damping.rayleigh[1]"),
    ("[damping]\nrayleigh = [0, 0]", "both coefficients are 0"),
    ("[damping]\nzeta = 0.1", "damping.zeta: unknown key"),
    ("[damping]", "give exactly one damping model"),
    ('[damping]\nrayleigh = "a"', "damping.rayleigh: 'a': not a list of two coefficients"),
])
def test_bad_damping_is_refused_in_one_line(extra, expect, tmp_path, capsys):
    assert "accepted:" in refused_scene(write_scene(tmp_path, "dm", three_mass_text(extra)), capsys, expect)


def test_repeated_frequency_with_proportional_dashpots(tmp_path, capsys):
    """ring4 with a dashpot beside every spring: C = (c/k) K, so zeta_j = c*omega_j/(2k) also for the
    repeated pair (whatever basis of it the eigen-solver picks); the rigid mode has no ratio."""
    text = (ROOT / "scenes" / "ring4.toml").read_text().replace("k = 1.0\n", "k = 1.0\nc = 0.1\n", 1)
    for a, b in (("m1", "m2"), ("m2", "m3"), ("m3", "m4"), ("m4", "m1")):
        text = text.replace("[initial]", f'[[dampers]]\nbetween = ["{a}", "{b}"]\nc = "c"\n\n[initial]')
    data = modes_json(text, tmp_path, capsys)
    assert data["damping"]["proportional"] is True
    ratios = [r["damping_ratio"] for r in data["modes"]]
    assert ratios[0] is None
    w = np.sqrt([r["omega2_value"] for r in data["modes"][1:]])
    assert ratios[1:] == pytest.approx(0.1 * w / 2, rel=1e-13)
