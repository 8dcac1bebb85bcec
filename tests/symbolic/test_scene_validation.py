"""Bad input: every hostile or malformed scene gets one clear line, exit 2, and nothing is written.

The corpus ``tests/hostile/*.toml`` holds one hostile case per file; its first
lines say what it tries (``# tries:``) and a piece of the expected message
(``# expect:``). Each file goes through ``modes``, ``simulate`` and ``derive``
in-process (the CLI's ``main``), with ``SPRINGCHAIN_CACHE`` in a temporary
folder, and must leave that folder and the output folder empty.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers import one_line_error as assert_one_line_error
from helpers import run_cli
from springchain.derive.errors import SceneError, one_line
from springchain._scenes import bundled_scenes
from springchain.derive.scene import RESERVED, load_scene

HOSTILE = Path(__file__).resolve().parents[1] / "hostile"
CASES = sorted(HOSTILE.glob("*.toml"))
PWNED = Path("/tmp/springchain-pwned")


def _header(path: Path) -> dict[str, str]:
    head = {}
    for line in path.read_bytes().decode("utf-8", "replace").splitlines()[:3]:
        m = re.match(r"# (tries|expect|commands): (.*)", line)
        if m:
            head[m.group(1)] = m.group(2).strip()
    return head


def files_under(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*")) if folder.exists() else []


# -- the corpus ---------------------------------------------------------------------------
def test_corpus_is_large_and_documented():
    assert len(CASES) >= 30
    for path in CASES:
        head = _header(path)
        assert head.get("tries"), f"{path.name}: first line must say '# tries: ...'"
        assert head.get("expect"), f"{path.name}: second line must say '# expect: ...'"


@pytest.mark.parametrize("command", ["modes", "simulate", "derive"])
@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_hostile_scene_is_refused_in_one_line(path, command, tmp_path, monkeypatch, capsys):
    cache, out_dir = tmp_path / "cache", tmp_path / "out"
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(cache))
    refused_by = _header(path).get("commands", "modes simulate derive").split()
    if command not in refused_by:  # a setting only the commands that use it check (e.g. [simulation])
        monkeypatch.setenv("SPRINGCHAIN_PROGRESS", "0")  # real work: a loaded machine may show progress
        argv = {"modes": ["modes", path], "simulate": [], "derive": ["derive", path, "--out", out_dir]}[command]
        status, out, err = run_cli(argv, capsys)
        assert status == 0 and err == "", err
        return
    argv = {"modes": ["modes", path],
            "simulate": ["simulate", path, "--out", out_dir, "--no-figures"],
            "derive": ["derive", path, "--out", out_dir]}[command]
    status, out, err = run_cli(argv, capsys)
    line = assert_one_line_error(status, out, err, path.name, _header(path)["expect"])
    assert str(path) in line  # the file as the user gave it
    assert out == ""
    assert files_under(out_dir) == [] and files_under(cache) == []
    assert not PWNED.exists()


def test_derive_validates_every_scene_before_writing(tmp_path, monkeypatch, capsys, seed_path):
    """A good scene followed by a bad one: nothing is written at all."""
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    status, out, err = run_cli(["derive", seed_path, HOSTILE / "spring_self.toml", "--out",
                                tmp_path / "gen"], capsys)
    assert_one_line_error(status, out, err, "spring_self.toml", "itself")
    assert files_under(tmp_path / "gen") == []


# -- command-line options -------------------------------------------------------------------
@pytest.mark.parametrize("options, expect", [
    (["--dt", "0"], "--dt"),
    (["--dt", "nan"], "--dt"),
    (["--dt", "inf"], "--dt"),
    (["--dt", "-0.1"], "--dt"),
    (["--dt", "abc"], "--dt"),
    (["--steps", "-1"], "--steps"),
    (["--steps", "0"], "--steps"),
    (["--steps", "1.5"], "--steps"),
    (["--record-every", "0"], "--record-every"),
    (["--method", "bogus"], "bogus"),
    (["--spectrum", "guess"], "guess"),
], ids=lambda v: "_".join(v) if isinstance(v, list) else None)
def test_bad_option_is_refused_in_one_line(options, expect, tmp_path, monkeypatch, capsys, seed_path):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    status, out, err = run_cli(["simulate", seed_path, "--out", tmp_path / "out", *options], capsys)
    assert_one_line_error(status, out, err, expect)
    assert files_under(tmp_path / "out") == []


def test_steps_option_beyond_memory_says_how_much(tmp_path, monkeypatch, capsys, seed_path):
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))
    status, out, err = run_cli(["simulate", seed_path, "--out", tmp_path / "out", "--steps",
                                str(10**12)], capsys)
    line = assert_one_line_error(status, out, err, "seed.toml", "GiB")
    need = float(re.search(r"would need ([0-9.e+]+) GiB", line).group(1))
    assert need > 4  # 10^12 steps x 3 masses x 2 arrays x 8 bytes x 2 methods ~ 8.7e4 GiB
    assert files_under(tmp_path / "out") == []


@pytest.mark.parametrize("make", [lambda tmp: tmp / "missing.toml", lambda tmp: tmp],
                         ids=["missing", "directory"])
def test_unreadable_scene_file(make, tmp_path, capsys):
    status, out, err = run_cli(["modes", make(tmp_path)], capsys)
    assert_one_line_error(status, out, err, "cannot read")


# -- messages --------------------------------------------------------------------------------
SEED_TEXT = """name = "s"
[parameters]
m = 1.0
k = 1.0
[masses]
m1 = "m"
m2 = "m"
[[springs]]
between = ["m1", "m2"]
k = "k"
[initial]
x = [0.1, 0.0]
v = [0.0, 0.0]
"""


def refused(text: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene("t.toml", text=text)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("t.toml: ")
    return info.value


@pytest.mark.parametrize("old, new, key, suggestion", [
    ('k = "k"\n[initial]', 'stiffness = "k"\n[initial]', "springs[0].stiffness", "'k'"),
    ('between = ["m1", "m2"]', 'ends = ["m1", "m2"]', "springs[0].ends", "'between'"),
    ("[initial]", "[initail]", "initail", "'initial'"),
    ("[parameters]", "[params]", "params", "'parameters'"),
    ("x = [0.1, 0.0]", "positions = [0.1, 0.0]", "initial.positions", "'x'"),
    ("[initial]", "[simulation]\nDT = 0.1\n[initial]", "simulation.DT", "'dt'"),
    ("[initial]", "[simulation]\nnsteps = 10\n[initial]", "simulation.nsteps", "'steps'"),
    ("[initial]", "[[dampers]]\nbetween = [\"m1\", \"wall\"]\ndamping = 1.0\n[initial]",
     "dampers[0].damping", "'c'"),
])
def test_unknown_key_suggests_the_right_one(old, new, key, suggestion):
    assert old in SEED_TEXT
    err = refused(SEED_TEXT.replace(old, new, 1))
    assert err.key == key
    assert f"did you mean {suggestion}?" in str(err)
    assert "accepted: " in str(err)


def test_unknown_mass_suggests_a_near_name():
    err = refused(SEED_TEXT.replace('between = ["m1", "m2"]', 'between = ["m1", "m3"]'))
    assert "'m3'" in str(err) and "accepted: 'm1', 'm2', 'wall'" in str(err)
    err = refused(SEED_TEXT.replace('between = ["m1", "m2"]', 'between = ["m1", "M2"]'))
    assert "did you mean 'm2'?" in str(err)


def test_unknown_symbol_suggests_a_parameter():
    err = refused(SEED_TEXT.replace('k = "k"\n[initial]', 'k = "kk"\n[initial]'))
    assert err.key == "springs[0].k" and "'kk'" in str(err) and "did you mean 'k'?" in str(err)


def test_value_zero_in_exact_arithmetic_is_refused():
    """sin(pi) is 1.2e-16 in floating point but exactly 0: a mass of it would divide by zero."""
    err = refused(SEED_TEXT.replace('m1 = "m"', 'm1 = "sin(pi)"'))
    assert err.key == "masses.m1" and "rounding cannot tell from 0" in str(err)
    err = refused(SEED_TEXT.replace('k = "k"\n[initial]', 'k = "0.1 + 0.2 - 0.3"\n[initial]'))
    assert err.key == "springs[0].k"
    # small but certain values are fine
    scene = load_scene("t.toml", text=SEED_TEXT.replace('m1 = "m"', 'm1 = "1e-20 + 0*m"'))
    assert scene.mass_exprs[0].evaluate(scene.parameters) == pytest.approx(1e-20)


@pytest.mark.parametrize("value", ['"1e-200"', '"m*1e200"', "1e-320"])
def test_masses_out_of_range_are_refused(value):
    err = refused(SEED_TEXT.replace('m1 = "m"', f"m1 = {value}"))
    assert err.key == "masses.m1" and "1e-150" in str(err)


def test_chain_expressions_are_checked_at_every_index():
    chain = """name = "c"
[parameters]
m = 1.0
k = 1.0
[chain]
n = 200000
mass = "MASS"
k = "K"
left = "LEFT"
[initial]
x = "0"
v = "0"
[simulation]
record_every = 100
"""

    def text(mass="m", k="k", left="free"):
        return chain.replace("MASS", mass).replace('"K"', f'"{k}"').replace("LEFT", left)

    err = refused(text(mass="m*(150000 - i)"))  # negative from i = 150001 on (beyond one chunk)
    assert err.key == "chain.mass" and "at i = 150000" in str(err)
    # k at i = -1 is the left wall spring: checked only when there is a left wall
    load_scene("t.toml", text=text(k="k*(i + 1)"))
    err = refused(text(k="k*(i + 1)", left="wall"))
    assert err.key == "chain.k" and "at i = -1" in str(err)


def test_force_must_be_finite_over_the_run():
    text = SEED_TEXT + '[[forces]]\non = "m1"\nf = "sqrt(1 - t)"\n[simulation]\ndt = 0.1\nsteps = 100\n'
    err = refused(text)
    assert err.key == "forces[0].f" and "at t = " in str(err)
    load_scene("t.toml", text=text.replace("steps = 100", "steps = 10"))  # t_end = 1: fine


def test_initial_expression_for_chain_uses_i_and_n():
    text = """name = "c"
[parameters]
a0 = 0.5
[chain]
n = 5
mass = "1"
k = "1"
[initial]
x = "a0*sin(pi*(i + 1)/(n + 1))"
v = 0
"""
    scene = load_scene("t.toml", text=text)
    import numpy as np

    i = np.arange(5)
    assert np.allclose(scene.x0, 0.5 * np.sin(np.pi * (i + 1) / 6))
    assert np.allclose(scene.v0, 0.0)


@given(st.text(max_size=300), st.text(max_size=60), st.text(max_size=60))
def test_scene_error_is_always_one_printable_line(message, key, file):
    text = str(SceneError(file or None, key or None, message))
    assert "\n" not in text and "\r" not in text
    assert all(ch.isprintable() for ch in text)
    assert len(text) <= 2 * 120 + 400 + 4


def test_one_line_escapes_control_characters():
    assert one_line("a\nb\x1b[31m\u202e") == "a\\nb\\x1b[31m\\u202e"


# -- names -----------------------------------------------------------------------------------
def test_bundled_scenes_load():
    names = [load_scene(p).name for p in bundled_scenes()]
    assert "seed" in names


def body_names_not_private(source: str) -> set[tuple[str, str]]:
    """(function, name) for every name a public function's body reads that is neither one of
    its own arguments, a local it binds, ``i``/``n``/``t``, nor private (``_...``)."""
    tree = ast.parse(source)
    bad = set()
    for fn in tree.body:
        if not isinstance(fn, ast.FunctionDef) or fn.name.startswith("_"):
            continue
        own = {a.arg for a in fn.args.args + fn.args.kwonlyargs}
        for node in (m for st in fn.body for m in ast.walk(st)):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
                if not (node.id in own or node.id.startswith("_") or node.id in ("i", "n", "t")):
                    bad.add((fn.name, node.id))
    return bad


@pytest.mark.parametrize("path", sorted(p for p in (Path(__file__).resolve().parents[2] / "generated").glob("[!_]*.py")
                                       if p.stem != "contract"),  # the contract describes modules; it is none
                         ids=lambda p: p.stem)
def test_no_parameter_can_shadow_a_name_of_generated_code(path):
    """Parameters become keyword arguments of the generated functions: every other name a
    function body reads must be private (start with '_', which scene names never do)."""
    assert body_names_not_private(path.read_text(encoding="utf-8")) == set()


def test_only_the_scene_language_is_reserved_for_parameters():
    for name in ("t", "i", "n", "sqrt", "pi", "sin", "cos", "exp", "wall"):
        err = refused(SEED_TEXT.replace("k = 1.0", f"k = 1.0\n{name} = 2.0"))
        assert err.key == f"parameters.{name}" and "reserved" in str(err)
    assert RESERVED == {"t", "i", "n", "sqrt", "pi", "sin", "cos", "exp", "wall"}
    for name in ("x", "numpy", "out", "N", "K", "float", "len", "x_m9", "a_p", "match", "type", "case",
                 "masses", "energy", "omega2", "SCENE", "np"):
        scene = load_scene("s.toml", SEED_TEXT.replace("k = 1.0", f"k = 1.0\n{name} = 2.0"))
        assert name in scene.parameters


def test_mass_and_parameter_may_not_share_a_name():
    err = refused(SEED_TEXT.replace("k = 1.0", "k = 1.0\nm1 = 2.0"))
    assert err.key == "masses.m1" and "parameter" in str(err)
    err = refused(SEED_TEXT.replace("k = 1.0", "k = 1.0\nx_m1 = 2.0"))
    assert err.key == "parameters.x_m1" and "coordinate" in str(err)


@pytest.mark.parametrize("name", ["_", "lambda", "None", "True", "é", "m\u0430",
                                  "1m", "m 1", "m.1", "", "a" * 65])
def test_bad_names_are_refused_everywhere(name):
    quoted = '"' + name.replace('"', '\\"') + '"'
    for old, new in ((('name = "s"', f"name = {quoted}")),
                     ('m1 = "m"', f'{quoted} = "m"'),
                     ("k = 1.0", f"k = 1.0\n{quoted} = 2.0")):
        refused(SEED_TEXT.replace(old, new, 1))
