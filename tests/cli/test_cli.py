"""The ``springchain`` command, mostly in-process through ``derive.cli.main``.

One test runs the installed console script in a subprocess (import-time output,
the real entry point); the rest call ``main([...])`` and read stdout/stderr with capsys.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from springchain.cli import main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _snapshot(folder: Path) -> dict[str, tuple[int, int, bytes]]:
    """Name -> (mtime_ns, size, content) of every file below ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and "__pycache__" not in p.parts:
            st = p.stat()
            out[str(p.relative_to(folder))] = (st.st_mtime_ns, st.st_size, p.read_bytes())
    return out


def _numbers(text: str) -> list[float]:
    return [float(s) for s in re.findall(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?", text)]


@pytest.fixture
def in_repo(monkeypatch, repo_root):
    monkeypatch.chdir(repo_root)
    return repo_root


# -- modes ----------------------------------------------------------------------------------------------
def _check_modes_json(data: dict) -> None:
    assert {"scene", "parameters", "masses", "modes"} <= set(data)
    assert data["scene"] == "seed"
    assert data["parameters"] == {"k": 1.0, "m": 1.0}
    assert data["masses"] == ["m1", "m2", "m3"]
    modes = data["modes"]
    assert len(modes) == 3
    values = [mode["omega2_value"] for mode in modes]
    assert values == sorted(values)
    np.testing.assert_allclose(values, [0.0, 1.0, 5 / 3], rtol=1e-15, atol=1e-15)
    m, k = sp.Symbol("m", positive=True), sp.Symbol("k", positive=True)
    loc = {"m": m, "k": k}
    expected = [(sp.Integer(0), [1, 1, 1]), (k / m, [1, 0, -1]), (5 * k / (3 * m), [1, sp.Rational(-2, 3), 1])]
    for mode, (w2, shape_ref) in zip(modes, expected):
        assert set(mode) >= {"omega2", "omega2_value", "multiplicity", "shape", "shape_value"}
        assert mode["multiplicity"] == 1
        got = sp.sympify(mode["omega2"], locals=loc)
        assert sp.simplify(got - w2) == 0, (mode["omega2"], w2)
        shape = [sp.sympify(c, locals=loc) for c in mode["shape"]]
        assert len(shape) == 3
        assert any(c != 0 for c in shape)
        for i in range(3):
            for j in range(i + 1, 3):
                assert sp.simplify(shape[i] * shape_ref[j] - shape[j] * shape_ref[i]) == 0, (shape, shape_ref)
        sv = np.array(mode["shape_value"], dtype=float)
        ref = np.array(shape_ref, dtype=float)
        np.testing.assert_allclose(sv / np.linalg.norm(sv) * np.sign(sv @ ref), ref / np.linalg.norm(ref),
                                   atol=1e-14)


def test_modes_json(in_repo, capsys):
    assert main(["modes", "scenes/seed.toml", "--json"]) == 0
    out = capsys.readouterr().out
    data = json.loads(out)  # exactly one JSON object, nothing else on stdout
    assert isinstance(data, dict)
    _check_modes_json(data)


def test_console_script_modes_json(repo_root):
    """The installed entry point prints exactly one JSON object (no stray output at import)."""
    exe = Path(sys.executable).with_name("springchain")
    if not exe.exists():
        found = shutil.which("springchain")
        if found is None:
            pytest.skip("springchain console script not installed")
        exe = Path(found)
    out = subprocess.run([str(exe), "modes", "scenes/seed.toml", "--json"], cwd=repo_root,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    decoder = json.JSONDecoder()
    data, end = decoder.raw_decode(out.stdout.strip())
    assert end == len(out.stdout.strip())
    _check_modes_json(data)


def test_modes_text_and_latex(in_repo, capsys):
    assert main(["modes", "scenes/seed.toml"]) == 0
    text = capsys.readouterr().out
    assert "5*k/(3*m)" in text and "k/m" in text
    assert main(["modes", "scenes/seed.toml", "--latex"]) == 0
    latex = capsys.readouterr().out
    assert r"\begin{align*}" in latex and r"\end{align*}" in latex
    assert r"\frac{5 k}{3 m}" in latex


def test_modes_bad_scene_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[parameters]\nm = 1.0\n[masses]\np = "m"\n'
                   '[[springs]]\nbetween = ["p", "nowhere"]\nk = "m"\n[initial]\nx = [0.0]\nv = [0.0]\n')
    assert main(["modes", str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "springs[0].between" in err and "nowhere" in err


# -- derive -----------------------------------------------------------------------------------------------
def test_derive_check_passes_in_repo_root(in_repo, capsys):
    before = _snapshot(in_repo / "generated")
    assert main(["derive", "--check"]) == 0
    out = capsys.readouterr().out
    assert "seed.py" in out and "STALE" not in out
    assert _snapshot(in_repo / "generated") == before


def test_derive_check_fails_on_modified_copy_and_writes_nothing(in_repo, tmp_path, capsys):
    out_dir = tmp_path / "gen"
    out_dir.mkdir()
    text = (in_repo / "generated" / "seed.py").read_text(encoding="utf-8")
    modified = text.replace("5/3", "5/4")
    assert modified != text
    (out_dir / "seed.py").write_text(modified, encoding="utf-8")
    before = _snapshot(out_dir)
    repo_before = _snapshot(in_repo / "generated")
    rc = main(["derive", "scenes/seed.toml", "--check", "--out", str(out_dir)])
    assert rc != 0
    assert "STALE" in capsys.readouterr().out
    assert _snapshot(out_dir) == before
    assert _snapshot(in_repo / "generated") == repo_before


def test_derive_check_fails_when_module_missing(in_repo, tmp_path, capsys):
    out_dir = tmp_path / "empty"
    out_dir.mkdir()
    assert main(["derive", "scenes/seed.toml", "--check", "--out", str(out_dir)]) != 0
    assert list(out_dir.iterdir()) == []


def test_derive_writes_module_equal_to_checked_in(in_repo, tmp_path, capsys):
    out_dir = tmp_path / "gen"
    repo_before = _snapshot(in_repo / "generated")
    assert main(["derive", "scenes/seed.toml", "--out", str(out_dir)]) == 0
    assert "wrote" in capsys.readouterr().out
    written = (out_dir / "seed.py").read_bytes()
    assert written == (in_repo / "generated" / "seed.py").read_bytes()
    assert sorted(p.name for p in out_dir.iterdir()) == ["seed.py"]  # no temp files left behind
    assert _snapshot(in_repo / "generated") == repo_before


# -- simulate -----------------------------------------------------------------------------------------------
def test_simulate_writes_npz_and_figures(in_repo, tmp_path, capsys):
    out_dir = tmp_path / "sim"
    assert main(["simulate", "scenes/seed.toml", "--out", str(out_dir)]) == 0
    printed = capsys.readouterr().out
    with np.load(out_dir / "seed.npz") as data:
        assert set(data.files) == {"t", "x_modal", "v_modal", "x_verlet", "v_verlet"}
        assert data["t"].shape == (1001,)
        np.testing.assert_allclose(data["t"], np.arange(1001) * 0.1, rtol=0, atol=0)
        for key in ("x_modal", "v_modal", "x_verlet", "v_verlet"):
            assert data[key].shape == (1001, 3)
            assert np.all(np.isfinite(data[key]))
        np.testing.assert_allclose(data["x_modal"][0], [0.8552, 1.5376, 0.8834], rtol=1e-14)
        np.testing.assert_allclose(data["v_verlet"][0], [-1.9255, 0.6991, -0.2460], rtol=1e-14)
        diff = np.abs(data["x_verlet"] - data["x_modal"]).max()
    assert 0.05 < diff < 0.2
    pngs = sorted(out_dir.glob("*.png"))
    assert len(pngs) >= 4  # positions, velocities, verlet - exact, energy
    names = " ".join(p.name for p in pngs)
    assert "position" in names and "velocit" in names and "energy" in names and "minus-exact" in names
    for p in pngs:
        assert p.read_bytes()[:8] == PNG_MAGIC
    # the largest differences and the energy drift are printed
    assert f"{diff:.3e}" in printed
    assert "energy drift" in printed


def test_simulate_beyond_stability_exits_2_with_one_line(in_repo, tmp_path, capsys):
    out_dir = tmp_path / "sim"
    rc = main(["simulate", "scenes/seed.toml", "--method", "verlet", "--dt", "5", "--out", str(out_dir)])
    assert rc == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    line = lines[0]
    assert re.search(r"ω_max|omega_max", line), line
    numbers = _numbers(line)
    w_max = np.sqrt(5 / 3)
    assert any(abs(x - w_max) < 1e-4 for x in numbers), line   # ω_max = 1.29099...
    assert any(abs(x - 2 / w_max) < 1e-4 for x in numbers), line  # dt limit 2/ω_max = 1.54919...
    assert not (out_dir / "seed.npz").exists()


def test_simulate_rejects_bad_option_with_exit_2(in_repo, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "scenes/seed.toml", "--dt", "-1"])
    assert exc.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


# -- run ------------------------------------------------------------------------------------------------------
def test_run_prints_fresh_and_writes_figures(tmp_path, monkeypatch, repo_root, capsys):
    monkeypatch.chdir(tmp_path)  # `run` needs no arguments and works from anywhere
    repo_before = _snapshot(repo_root / "generated")
    out_dir = tmp_path / "out"
    assert main(["run", "--out", str(out_dir)]) == 0
    printed = capsys.readouterr().out
    assert "fresh" in printed and "STALE" not in printed
    assert "5*k/(3*m)" in printed
    assert (out_dir / "seed.npz").exists()
    assert len(list(out_dir.glob("*.png"))) >= 4
    assert str(out_dir.resolve()) in printed
    assert _snapshot(repo_root / "generated") == repo_before


# -- a user's scene outside the repository ----------------------------------------------------------------------
USER_SCENE = """
name = "mine"
description = "two masses on a wall spring"
[parameters]
m = 2.0
k = 5.0
[masses]
a1 = "m"
a2 = "m/2"
[[springs]]
between = ["wall", "a1"]
k = "k"
[[springs]]
between = ["a1", "a2"]
k = "2*k"
[initial]
x = [0.1, -0.2]
v = [0.0, 0.3]
[simulation]
dt = 0.05
steps = 200
"""


def test_user_scene_outside_repo_uses_cache(tmp_path, monkeypatch, repo_root, capsys):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(cache))
    user_dir = tmp_path / "user"
    user_dir.mkdir()
    scene = user_dir / "mine.toml"
    scene.write_text(USER_SCENE, encoding="utf-8")
    monkeypatch.chdir(user_dir)
    repo_before = _snapshot(repo_root / "generated")
    repo_listing = sorted(p.name for p in (repo_root / "generated").iterdir())

    assert main(["modes", str(scene), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["scene"] == "mine" and data["masses"] == ["a1", "a2"]
    # K = [[3k, -2k], [-2k, 2k]], M = diag(m, m/2)
    K = np.array([[15.0, -10.0], [-10.0, 10.0]])
    M = np.diag([2.0, 1.0])
    import scipy.linalg

    np.testing.assert_allclose([mode["omega2_value"] for mode in data["modes"]],
                               scipy.linalg.eigh(K, M, eigvals_only=True), rtol=1e-13)

    out_dir = tmp_path / "sim"
    assert main(["simulate", str(scene), "--out", str(out_dir)]) == 0
    printed = capsys.readouterr().out
    assert "cache" in printed
    with np.load(out_dir / "mine.npz") as npz:
        assert npz["x_verlet"].shape == (201, 2) and npz["x_modal"].shape == (201, 2)
    cached = list(cache.glob("*.py"))
    assert len(cached) == 1 and cached[0].name.startswith("mine-")
    assert "import sympy" not in cached[0].read_text(encoding="utf-8")
    # a second simulate reuses the cached module (not rewritten)
    stamp = cached[0].stat().st_mtime_ns
    assert main(["simulate", str(scene), "--out", str(out_dir), "--no-figures"]) == 0
    capsys.readouterr()
    assert cached[0].stat().st_mtime_ns == stamp

    assert sorted(p.name for p in (repo_root / "generated").iterdir()) == repo_listing
    assert _snapshot(repo_root / "generated") == repo_before
    assert not (user_dir / "generated").exists()
    assert sorted(p.name for p in user_dir.iterdir()) == ["mine.toml"]
    assert os.environ["SPRINGCHAIN_CACHE"] == str(cache)
