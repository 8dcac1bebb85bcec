"""Scenes changed from Python (issue 23, item 1): ``with_parameters``, ``with_initial``,
``scene_from_dict`` and ``dataclasses.replace`` give validated scenes that every function honours.

Each function is run twice: on a scene changed through the API, and on a scene FILE written in the
test with the same values; the results must agree (and differ from the unchanged scene's).
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import numpy as np
import pytest

import springchain as sc
from springchain._modules import system_of
from springchain.cli import main

BASE = """name = "user"
[parameters]
m = 1.0
k = 1.0
[masses]
m1 = "m"
m2 = "3*m"
m3 = "m"
[[springs]]
between = ["m1", "m2"]
k = "k"
[[springs]]
between = ["m2", "m3"]
k = "k"
[initial]
x = [0.8552, 1.5376, 0.8834]
v = [-1.9255, 0.6991, -0.2460]
[simulation]
dt = 0.1
steps = 200
"""
NEW_X = [0.1, -0.2, 0.05]
NEW_V = [0.0, 0.3, -0.1]
#: The changed values written as a file: k = 4, m = 2 and another initial state.
CHANGED = (BASE.replace("m = 1.0", "m = 2.0").replace("k = 1.0", "k = 4.0")
           .replace("x = [0.8552, 1.5376, 0.8834]", f"x = {NEW_X}").replace("v = [-1.9255, 0.6991, -0.2460]", f"v = {NEW_V}"))


@pytest.fixture()
def scenes(tmp_path):
    """(unchanged file scene, the same changed through the API, the changed values as a file)."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "user.toml").write_text(BASE)
    (tmp_path / "b" / "user.toml").write_text(CHANGED)
    base = sc.load(tmp_path / "a" / "user.toml")
    changed = base.with_parameters(k=4.0, m=2.0).with_initial(x=np.array(NEW_X), v=NEW_V)
    return base, changed, sc.load(tmp_path / "b" / "user.toml")


def test_changed_scene_is_the_file_with_those_values(scenes):
    base, changed, ref = scenes
    assert changed.parameters == ref.parameters == {"k": 4.0, "m": 2.0}
    np.testing.assert_array_equal(changed.x0, ref.x0)
    np.testing.assert_array_equal(changed.v0, ref.v0)
    assert base.parameters == {"k": 1.0, "m": 1.0}  # the original is untouched
    np.testing.assert_array_equal(base.x0, [0.8552, 1.5376, 0.8834])
    assert changed.sha256 not in (base.sha256,)  # its own cache key


def test_modes_honour_the_change(scenes):
    base, changed, ref = scenes
    got, want = sc.modes(changed).omega2_values, sc.modes(ref).omega2_values
    np.testing.assert_allclose(got, want, rtol=1e-15)
    np.testing.assert_allclose(want, [0.0, 2.0, 10.0 / 3.0], rtol=1e-15)  # k/m, 5k/(3m) at k = 4, m = 2


def test_simulate_honours_the_change_and_never_aliases_the_file_module(scenes, tmp_path):
    base, changed, ref = scenes
    run = sc.simulate(changed, ["modal", "verlet"], steps=100, progress=False)  # the changed scene first
    want = sc.simulate(ref, ["modal", "verlet"], steps=100, progress=False)
    for m in ("modal", "verlet"):
        np.testing.assert_allclose(run.x[m], want.x[m], rtol=0, atol=1e-13)
        np.testing.assert_allclose(run.v[m], want.v[m], rtol=0, atol=1e-13)
    # the unchanged file afterwards still runs with its own values (k = m = 1), from its own module
    again = sc.simulate(base, ["modal"], steps=100, progress=False)
    module_base, _ = system_of(base)
    module_changed, _ = system_of(changed)
    assert module_base.module.DEFAULTS == {"k": 1.0, "m": 1.0}
    assert module_changed.module.DEFAULTS == {"k": 4.0, "m": 2.0}
    assert module_base.module.__file__ != module_changed.module.__file__
    w = np.sqrt([1.0, 5.0 / 3.0])  # exact solution of the unchanged file, built here from its numbers
    assert np.isclose(sc.modes(base).omega2_values[1:], w**2).all()
    x0, v0 = np.array([0.8552, 1.5376, 0.8834]), np.array([-1.9255, 0.6991, -0.2460])
    M = np.diag([1.0, 3.0, 1.0])
    K = np.array([[1.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    import scipy.linalg

    lam, phi = scipy.linalg.eigh(K, M)
    q0, dq0 = phi.T @ M @ x0, phi.T @ M @ v0
    t = again.t
    om = np.sqrt(np.maximum(lam, 0))
    q = q0 * np.cos(np.outer(t, om)) + dq0 * np.where(om > 1e-12, np.sin(np.outer(t, om)) / np.where(om > 1e-12, om, 1),
                                                      t[:, None])
    np.testing.assert_allclose(again.x["modal"], q @ phi.T, atol=1e-9)


def test_frf_honours_the_change(scenes):
    base, changed, ref = scenes
    got = sc.frf(changed, "m1", "m3", omega_min=0.5, omega_max=5.0, points=50, transfer=False)
    want = sc.frf(ref, "m1", "m3", omega_min=0.5, omega_max=5.0, points=50, transfer=False)
    old = sc.frf(base, "m1", "m3", omega_min=0.5, omega_max=5.0, points=50, transfer=False)
    np.testing.assert_allclose(got.omega, want.omega, rtol=1e-14)
    np.testing.assert_allclose(got.magnitude, want.magnitude, rtol=1e-12)
    assert got.omega.shape != old.omega.shape or not np.allclose(got.magnitude, old.magnitude)


def test_plan_honours_the_change(scenes):
    base, changed, ref = scenes
    got, want = sc.plan(changed, 1e-3, t_end=10.0), sc.plan(ref, 1e-3, t_end=10.0)
    old = sc.plan(base, 1e-3, t_end=10.0)
    key = lambda p: {c.name: (c.dt, c.rtol, c.predicted_error) for c in p.candidates}  # noqa: E731
    g, w, o = key(got), key(want), key(old)
    assert g.keys() == w.keys()
    for name in g:  # step sizes and predicted errors come from the model, not from timings
        for a, b in zip(g[name], w[name]):
            assert (a is None and b is None) or np.isclose(a, b, rtol=1e-9), (name, g[name], w[name])
    assert not np.isclose(g["verlet"][0], o["verlet"][0], rtol=1e-3)  # a stiffer scene needs another step


def test_bench_honours_the_change(scenes):
    base, changed, ref = scenes
    got = sc.bench(changed, 10.0, quick=True, methods=["verlet"])
    want = sc.bench(ref, 10.0, quick=True, methods=["verlet"])
    old = sc.bench(base, 10.0, quick=True, methods=["verlet"])
    errors = lambda r: {(x.method, x.setting): x.error for x in r.records}  # noqa: E731
    g, w = errors(got), errors(want)
    assert g.keys() == w.keys()
    for k in g:
        assert np.isclose(g[k], w[k], rtol=1e-6, atol=1e-15), (k, g[k], w[k])
    assert errors(old) != g


def test_animate_honours_the_change(scenes, tmp_path):
    base, changed, ref = scenes
    got = sc.animate(changed, mode=1, frames=4, out=tmp_path / "a")
    want = sc.animate(ref, mode=1, frames=4, out=tmp_path / "b")
    old = sc.animate(base, mode=1, frames=4, out=tmp_path / "c")
    assert np.isclose(got.omega, want.omega, rtol=1e-14) and np.isclose(got.omega, 2.0**0.5, rtol=1e-14)
    assert not np.isclose(old.omega, got.omega)
    digest = lambda p: hashlib.sha256(Path(p).read_bytes()).hexdigest()  # noqa: E731
    assert digest(got.path) == digest(want.path)
    run = sc.animate(changed, method="modal", frames=4, out=tmp_path / "d")
    assert run.frames == 4


# -- validation ---------------------------------------------------------------------------------------
def test_bad_changes_are_refused_in_one_line_like_the_file(scenes, tmp_path):
    base, _, _ = scenes
    with pytest.raises(sc.SceneError) as api:
        base.with_parameters(m=-1.0)
    bad = tmp_path / "bad.toml"
    bad.write_text(BASE.replace("m = 1.0", "m = -1.0"))
    with pytest.raises(sc.SceneError) as file:
        sc.load(bad)
    assert api.value.key == file.value.key == "masses.m1"
    assert api.value.detail == file.value.detail
    assert "with_parameters(m = -1.0)" in str(api.value) and "\n" not in str(api.value)
    with pytest.raises(sc.SceneError, match=r"parameters.kk: not a parameter .*did you mean 'k'"):
        base.with_parameters(kk=2.0)
    with pytest.raises(sc.SceneError, match=r"not a number"):
        base.with_parameters(k="4")
    with pytest.raises(sc.SceneError, match=r"2 values for 3 masses"):
        base.with_initial(x=[1.0, 2.0])
    with pytest.raises(sc.SceneError, match=r"initial.v\[1\]: nan: not a finite number"):
        base.with_initial(v=np.array([0.0, np.nan, 0.0]))
    with pytest.raises(sc.SceneError, match=r"shape \(2, 3\)"):
        base.with_initial(x=np.zeros((2, 3)))


def test_dataclasses_replace_is_validated_or_refused(scenes):
    base, _, ref = scenes
    new = dataclasses.replace(base, parameters={"k": 4.0, "m": 2.0}, x0=np.array(NEW_X), v0=np.array(NEW_V))
    assert new.parameters == ref.parameters and new.sha256 != base.sha256
    np.testing.assert_allclose(sc.modes(new).omega2_values, sc.modes(ref).omega2_values, rtol=1e-15)
    np.testing.assert_allclose(sc.simulate(new, ["modal"], steps=20, progress=False).x["modal"],
                               sc.simulate(ref, ["modal"], steps=20, progress=False).x["modal"], atol=1e-13)
    with pytest.raises(sc.SceneError, match="masses.m1: 'm': evaluates to -1"):
        dataclasses.replace(base, parameters={"k": 1.0, "m": -1.0})
    with pytest.raises(sc.SceneError, match=r"replace\(springs=\.\.\.\).*cannot be replaced"):
        dataclasses.replace(base, springs=())
    with pytest.raises(sc.SceneError, match="steps"):
        dataclasses.replace(base, steps=0)
    assert dataclasses.replace(base, dt=0.05).dt == 0.05


def test_direct_construction_is_refused():
    fields = {f.name: None for f in dataclasses.fields(sc.Scene) if f.name != "source"}
    with pytest.raises(sc.SceneError, match="springchain.load"):
        sc.Scene(**fields)


# -- scene_from_dict ----------------------------------------------------------------------------------
def _seed_dict() -> dict:
    return {"name": "seed", "description": "from a dict", "parameters": {"m": 1.0, "k": 1.0},
            "masses": {"m1": "m", "m2": "3*m", "m3": "m"},
            "springs": [{"between": ["m1", "m2"], "k": "k"}, {"between": ["m2", "m3"], "k": "k"}],
            "initial": {"x": np.array([0.8552, 1.5376, 0.8834]), "v": [-1.9255, 0.6991, -0.2460]},
            "simulation": {"dt": 0.1, "steps": 100}}


def test_scene_from_dict_is_the_file(seed_path):
    d = sc.scene_from_dict(_seed_dict())
    f = sc.load(seed_path)
    assert (d.n, d.mass_names, d.parameters) == (f.n, f.mass_names, f.parameters)
    np.testing.assert_array_equal(d.x0, f.x0)
    assert sc.modes(d).omega2 == sc.modes(f).omega2
    np.testing.assert_allclose(sc.simulate(d, ["modal"], progress=False).x["modal"],
                               sc.simulate(f, ["modal"], steps=100, progress=False).x["modal"], atol=1e-13)
    assert sc.load(_seed_dict()).parameters == f.parameters  # load takes a dict too
    with pytest.raises(sc.SceneError, match=r"<dict>: springs\[0\].between: 'm9': not a mass"):
        sc.scene_from_dict({**_seed_dict(), "springs": [{"between": ["m9", "m2"], "k": "k"}]})
    with pytest.raises(sc.SceneError, match="not a dict"):
        sc.scene_from_dict([1, 2])


def test_force_and_ground_records_as_arrays_equal_the_csv_tables(tmp_path):
    t = np.linspace(0.0, 2.0, 21)
    f = np.sin(3.0 * t) * (t < 1.5)
    a = 0.5 * np.cos(2.0 * t)
    (tmp_path / "f.csv").write_text("t,f\n" + "\n".join(f"{float(x)!r},{float(y)!r}" for x, y in zip(t, f)) + "\n")
    (tmp_path / "a.csv").write_text("t,a\n" + "\n".join(f"{float(x)!r},{float(y)!r}" for x, y in zip(t, a)) + "\n")
    text = ('name = "rec"\n[parameters]\nm = 1.0\nk = 4.0\nc = 0.1\n[masses]\np = "m"\nq = "m"\n'
            '[[springs]]\nbetween = ["wall", "p"]\nk = "k"\n[[springs]]\nbetween = ["p", "q"]\nk = "k"\n'
            '[[dampers]]\nbetween = ["p", "wall"]\nc = "c"\n'
            '[[forces]]\non = "q"\ntable = "f.csv"\n[ground]\ntable = "a.csv"\n[simulation]\ndt = 0.01\nsteps = 300\n')
    (tmp_path / "rec.toml").write_text(text)
    ref = sc.load(tmp_path / "rec.toml")
    d = {"name": "rec", "parameters": {"m": 1.0, "k": 4.0, "c": 0.1}, "masses": {"p": "m", "q": "m"},
         "springs": [{"between": ["wall", "p"], "k": "k"}, {"between": ["p", "q"], "k": "k"}],
         "dampers": [{"between": ["p", "wall"], "c": "c"}],
         "forces": [{"on": "q", "table": np.column_stack([t, f])}], "ground": {"table": {"t": t, "a": a}},
         "simulation": {"dt": 0.01, "steps": 300}}
    mine = sc.scene_from_dict(d)
    np.testing.assert_array_equal(mine.table_forces[0].table.y, ref.table_forces[0].table.y)
    np.testing.assert_array_equal(mine.ground.table.y, ref.ground.table.y)
    run, want = (sc.simulate(s, ["modal", "verlet"], progress=False) for s in (mine, ref))
    for m in ("modal", "verlet"):
        np.testing.assert_allclose(run.x[m], want.x[m], atol=1e-14)
    assert np.abs(run.x["modal"]).max() > 1e-3  # the records really drive it
    for bad, why in ((np.array([[0.0, 1.0]]), "1 rows"), (np.array([[0.0, 1.0], [0.0, 2.0]]), "not strictly increasing"),
                     (np.array([[0.0, np.inf], [1.0, 2.0]]), "row 1"), ({"t": [0, 1], "x": [1, 2]}, "keys"),
                     (np.zeros((3, 3)), "shape")):
        with pytest.raises(sc.SceneError, match=why):
            sc.scene_from_dict({**d, "forces": [{"on": "q", "table": bad}]})


def test_with_initial_takes_chain_expressions_and_arrays_without_a_loop():
    chain = sc.load("chain100k")
    x = np.sin(np.linspace(0, 3, chain.n))
    s = chain.with_initial(x=x, v="0.001*i/n")
    np.testing.assert_array_equal(s.x0, x)
    np.testing.assert_allclose(s.v0, 0.001 * np.arange(chain.n) / chain.n, rtol=1e-15)
    assert s.with_parameters(**chain.parameters) is s


# -- the command line ---------------------------------------------------------------------------------
def test_set_option_on_every_scene_command(tmp_path, capsys):
    import json

    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "user.toml").write_text(BASE)
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "user.toml").write_text(BASE.replace("k = 1.0", "k = 4.0"))
    assert main(["modes", str(tmp_path / "a" / "user.toml"), "--set", "k=4", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert main(["modes", str(tmp_path / "b" / "user.toml"), "--json"]) == 0
    want = json.loads(capsys.readouterr().out)
    assert got["modes"] == want["modes"] and got["parameters"] == {"k": 4.0, "m": 1.0}
    from springchain.cli import SCENE_COMMANDS, build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name in SCENE_COMMANDS:
        assert "--set NAME=VALUE" in sub.choices[name].format_help(), name
    for argv, part in ((["--set", "kk=4"], "did you mean 'k'"), (["--set", "k=x"], "not NAME=NUMBER"),
                       (["--set", "m=-1"], "with --set m=-1: masses.m1"),
                       (["--set", "k=2", "--set", "k=3"], "given twice")):
        assert main(["modes", str(tmp_path / "a" / "user.toml"), *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and part in err[0], err


def test_sweep_honours_the_change(scenes, tmp_path):
    base, changed, ref = scenes
    kw = dict(vary=["m=grid(1, 3, 3)"], samples=2, workers=1, progress=False)
    got = sc.sweep(changed, out=tmp_path / "a", **kw).table(["omega2"]).column("omega2").to_pylist()
    want = sc.sweep(ref, out=tmp_path / "b", **kw).table(["omega2"]).column("omega2").to_pylist()
    old = sc.sweep(base, out=tmp_path / "c", **kw).table(["omega2"]).column("omega2").to_pylist()
    np.testing.assert_allclose(got, want, rtol=1e-14)
    np.testing.assert_allclose(np.asarray(got)[:2, 1], 4.0, rtol=1e-14)  # k = 4 at m = 1: omega2 = k/m
    assert not np.allclose(got, old)
