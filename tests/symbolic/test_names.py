"""Users' own names: any identifier but a keyword, 'wall' and (for parameters) the scene language.

Scenes with names drawn from everything that was refused before (names generated code used,
builtins, module names, coordinate-like names) go through derive -> import -> simulate ->
``modes --json`` read back, and the results are checked against NumPy.
"""

from __future__ import annotations

import builtins
import json
import keyword
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers import scene_toml
from springchain import _api
from springchain.cli import main
from springchain.derive.scene import RESERVED, load_scene

#: Names refused before issue 10 (generated code's names, module names, coordinates, builtins).
ONCE_REFUSED = ("w K d f s e j omega out vec const col diag off idx kk inner extra parts ends xa xb "
                "N masses energy omega2 np numpy min sum len float x v a x_m1 SCENE PARAMETERS DEFAULTS "
                "MASS_NAMES EFFECTS LINEAR RIGID_MODES MAX_DENSE LEFT acceleration make_acceleration "
                "stiffness_matrix mass_matrix spring_constants scipy math sympy sp abs type print range "
                "ValueError match case t_ i_ cos_amp sin_amp inv_m").split()
PARAM_POOL = sorted(set(ONCE_REFUSED) | {n for n in dir(builtins) if n.isidentifier() and
                                         not n.startswith("_") and not keyword.iskeyword(n)})
PARAM_POOL = [n for n in PARAM_POOL if n not in RESERVED]
MASS_POOL = sorted(set(ONCE_REFUSED) | {"a", "x", "v", "t", "i", "n", "pi", "sqrt", "sin", "np", "numpy"})


def named_scene_text(masses, params, *, damper: bool, force: bool, gravity: bool) -> str:
    m, k, c, g = params[:4]
    ends = [[masses[0], "wall"]] + [[a, b] for a, b in zip(masses, masses[1:])]
    n = len(masses)
    return scene_toml("names", {m: 1.5, k: 2.0, c: 0.1, g: 0.3, **{p: 1.0 for p in params[4:]}},
                      masses={name: f"{m}*{j + 1}" for j, name in enumerate(masses)},
                      springs=[{"between": e, "k": k} for e in ends],
                      dampers=[{"between": [masses[-1], "wall"], "c": c}] if damper else (),
                      forces=[{"on": masses[0], "f": f"{g}*cos(t)"}] if force else (),
                      tables={"gravity": {"g": g}} if gravity else None,
                      initial={"x": [0.1] + [0.0] * (n - 1), "v": [0.0] * n}, simulation={"dt": 0.01, "steps": 40})


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                 HealthCheck.too_slow])
@given(masses=st.lists(st.sampled_from(MASS_POOL), min_size=1, max_size=3, unique=True),
       params=st.lists(st.sampled_from(PARAM_POOL), min_size=4, max_size=7, unique=True),
       damper=st.booleans(), force=st.booleans(), gravity=st.booleans())
def test_any_sensible_name_derives_runs_and_reads_back(masses, params, damper, force, gravity, tmp_path,
                                                       monkeypatch):
    params = [p for p in params if p not in masses and not any(p == f"{c}_{m}" for m in masses for c in "xva")]
    if len(params) < 4:
        return
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / f"s{abs(hash((tuple(masses), tuple(params), damper, force, gravity)))}.toml"
    path.write_text(named_scene_text(masses, params, damper=damper, force=force, gravity=gravity))
    scene = load_scene(path)
    assert scene.mass_names == tuple(masses)
    result = _api.simulate(scene)
    for name, x in result.x.items():
        assert np.all(np.isfinite(x)), name
    if "modal" in result.x:  # the exact solution and Verlet agree on this short run
        assert np.max(np.abs(result.x["modal"] - result.x["verlet"])) < 1e-3
    data = json.loads(json.dumps(_api.modes(scene).to_json()))
    assert data["scene"] == "names" and set(data["parameters"]) == set(params)
    # ω² read back equal the eigenvalues of M⁻¹K built here from the scene's values
    n, mval, kval = len(masses), 1.5, 2.0
    K = np.zeros((n, n))
    for a, b in [(0, -1)] + [(j, j + 1) for j in range(n - 1)]:
        K[a, a] += kval
        if b >= 0:
            K[b, b] += kval
            K[a, b] -= kval
            K[b, a] -= kval
    M = np.diag([mval * (j + 1) for j in range(n)])
    expect = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    got = np.sort(np.repeat([rec["omega2_value"] for rec in data["modes"]],
                            [rec["multiplicity"] for rec in data["modes"]]))
    np.testing.assert_allclose(got, expect, rtol=1e-9)


@pytest.mark.parametrize("params", [["K", "w", "d", "f", "s", "e", "omega", "j", "out", "N", "float"],
                                    ["len", "x", "v", "a", "sum", "min", "numpy", "np", "energy"]])
def test_chain_scene_with_once_refused_parameter_names(params, tmp_path, monkeypatch):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    m, k, *rest = params
    path = tmp_path / "c.toml"
    path.write_text("\n".join(['name = "c"', "[parameters]", f"{m} = 1.0", f"{k} = 1.0",
                               *[f"{p} = 0.5" for p in rest],
                               "[chain]", "n = 50", f'mass = "{m} + {rest[0]}*0"', f'k = "{k}"',
                               'left = "wall"', "[initial]", 'x = "0.01*sin(pi*(i+1)/(n+1))"', 'v = "0"',
                               "[simulation]", "dt = 0.05", "steps = 20"]) + "\n")
    result = _api.simulate(path, out=tmp_path / "out")
    assert np.all(np.isfinite(result.x["verlet"]))
    data = _api.modes(path).to_json()
    assert len(data["modes"]) > 0


@pytest.mark.parametrize("path", sorted((Path(__file__).resolve().parents[1] / "names_ok").glob("*.toml")),
                         ids=lambda p: p.stem)
@pytest.mark.parametrize("command", ["modes", "simulate"])
def test_once_refused_names_work_from_the_command_line(path, command, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    argv = [command, str(path)] + (["--out", str(tmp_path / "out")] if command == "simulate" else [])
    assert main(argv) == 0, capsys.readouterr().err


def test_mass_named_a_and_parameter_named_K(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "aK.toml"
    path.write_text('name = "aK"\n[parameters]\nm = 1.0\nK = 4.0\n[masses]\na = "m"\n'
                    '[[springs]]\nbetween = ["a", "wall"]\nk = "K"\n[initial]\nx = [1.0]\nv = [0.0]\n')
    assert main(["modes", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["masses"] == ["a"] and data["modes"][0]["omega2_value"] == pytest.approx(4.0)
    assert main(["simulate", str(path), "--out", str(tmp_path / "o")]) == 0
    assert main(["derive", str(path), "--out", str(tmp_path / "g")]) == 0
    assert (tmp_path / "g" / "aK.py").exists()


def _big_scene(n: int, *, cubic: bool) -> str:
    names = [f"q{j}" for j in range(n)]
    lines = ['name = "big"', "[parameters]", "m = 1.0", "k = 2.0", "c = 0.1", "g = 0.5", "[masses]"]
    lines += [f'{q} = "m"' for q in names]
    for a, b in [(names[0], "wall")] + list(zip(names, names[1:])):
        lines += ["[[springs]]", f'between = ["{a}", "{b}"]', 'k = "k"'] + (['k3 = "0.1"'] if cubic else [])
    lines += ["[[dampers]]", f'between = ["{names[-1]}", "wall"]', 'c = "c"',
              "[[forces]]", f'on = "{names[0]}"', 'f = "g*sin(t)"', "[gravity]", 'g = "g"',
              "[initial]", f"x = {[0.0] * n}", f"v = {[0.1] * n}"]
    return "\n".join(lines) + "\n"


def _chain(extra: str) -> str:
    return ('name = "ch"\n[parameters]\nm = 1.0\nk = 2.0\n[chain]\nn = 8\nmass = "m*(1 + i % 2)"\nk = "k"\n'
            + extra + '[initial]\nx = "0"\nv = "0.1"\n')


@pytest.mark.parametrize("text", [_big_scene(14, cubic=False), _big_scene(14, cubic=True), _big_scene(3, cubic=True),
                                  _chain('left = "ring"\nright = "ring"\n'), _chain('k3 = "0.2"\nleft = "wall"\n'),
                                  _chain('right = "wall"\n')],
                         ids=["dense-14-effects", "cubic-14-effects", "cubic-3-effects", "ring-nonuniform",
                              "chain-cubic-wall", "chain-free-wall"])
def test_every_kind_of_generated_module_keeps_its_names_private(text):
    from springchain._modules import derive
    from test_scene_validation import body_names_not_private

    source = derive(load_scene("s.toml", text=text)).source
    assert body_names_not_private(source) == set()
    compile(source, "generated", "exec")
