"""The Python API (springchain.load / modes / simulate / plan / bench) against the commands it backs.

* the API returns what the command prints (``modes --json``, the NPZ of ``simulate``);
* bad input raises :class:`springchain.SceneError` (a ValueError) with the command's one line;
* the README's notebook example runs as written;
* the one import namespace: only ``springchain`` at the top, no module loaded twice;
* the light method-name table agrees with the integrator registries.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import springchain
from springchain.cli import main

README = Path(__file__).resolve().parents[2] / "README.md"


def test_version_is_the_distribution_version(capsys):
    import importlib.metadata

    assert springchain.__version__ == importlib.metadata.version("springchain")
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"springchain {springchain.__version__}"


def test_load_by_bundled_name_and_by_path(seed_path):
    by_name = springchain.load("seed")
    by_path = springchain.load(seed_path)
    assert by_name.sha256 == by_path.sha256 and by_name.name == "seed"
    assert springchain.load(by_name) is by_name


def test_load_errors_are_scene_errors_with_the_command_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[masses]\nm1 = "-1"\n')
    with pytest.raises(springchain.SceneError) as exc:
        springchain.load(bad)
    assert isinstance(exc.value, ValueError)
    assert main(["modes", str(bad)]) == 2
    assert capsys.readouterr().err == f"springchain: error: {exc.value}\n"
    with pytest.raises(springchain.SceneError, match="not a bundled scene.*seed"):
        springchain.load("no_such_scene_name")


def test_modes_to_json_is_what_the_command_prints(capsys):
    m = springchain.modes("seed")
    assert main(["modes", "seed", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == m.to_json()
    import sympy as sp

    k, mm = sp.symbols("k m", positive=True)
    assert [sp.simplify(w - ref) for w, ref in zip(m.omega2, [0, k / mm, 5 * k / (3 * mm)])] == [0, 0, 0]
    np.testing.assert_allclose(m.omega2_values, [0.0, 1.0, 5 / 3], rtol=1e-15, atol=0)
    latex = m._repr_latex_()
    assert "\\frac" in latex and latex.strip().startswith(("$", "\\begin"))
    assert main(["modes", "seed"]) == 0
    assert capsys.readouterr().out == m.to_text()


def test_simulate_matches_the_command_npz(tmp_path):
    run = springchain.simulate("seed", steps=200)
    assert run.methods == ["modal", "verlet"]
    assert run.t.shape == (201,) and run.x["modal"].shape == (201, 3) and run.v["verlet"].shape == (201, 3)
    np.testing.assert_allclose(run.t, np.arange(201) * 0.1, rtol=0, atol=1e-15)
    assert main(["simulate", "seed", "--steps", "200", "--out", str(tmp_path / "cmd"), "--no-figures"]) == 0
    cmd = np.load(tmp_path / "cmd" / "seed.npz")
    saved = np.load(run.save(tmp_path / "api.npz"))
    assert sorted(cmd.files) == sorted(saved.files) == ["t", "v_modal", "v_verlet", "x_modal", "x_verlet"]
    for key in cmd.files:
        np.testing.assert_allclose(saved[key], cmd[key], rtol=1e-12, atol=1e-14)
    fig = run.plot()
    from matplotlib.figure import Figure

    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "time t [s]" and "position" in ax.get_ylabel() and ax.get_legend() is not None


def test_simulate_defaults_follow_the_scene(seed_path):
    scene = springchain.load(seed_path)
    run = springchain.simulate(scene, methods=["verlet"])
    assert run.t.shape == (scene.steps // scene.record_every + 1,)
    assert run.summary["dt"] == scene.dt and run.summary["steps"] == scene.steps
    with pytest.raises(springchain.RunRefused, match="method 'nope'.*accepted"):
        springchain.simulate(scene, methods=["nope"])
    with pytest.raises(springchain.RunRefused, match="dt"):
        springchain.simulate(scene, dt=-1.0)


def test_simulate_memory_is_checked_with_the_effective_settings(seed_path):
    scene = springchain.load(seed_path)
    with pytest.raises(springchain.SceneError, match="GiB"):
        springchain.simulate(scene, steps=10**12)
    run = springchain.simulate(scene, methods=["modal"], steps=10**6, record_every=10**5)  # 11 frames: fine
    assert run.t.shape == (11,)


def test_plan_and_bench_through_the_api():
    plan = springchain.plan("seed", tol=1e-3)
    assert plan.recommended.predicted_error <= 1e-3
    data = json.loads(json.dumps(plan.as_json()))  # plain JSON: the same object back
    assert data == plan.as_json() and data["recommended"]["method"] == plan.recommended.name
    assert data["recommended"] in data["candidates"] and len(data["candidates"]) == len(plan.candidates)
    result = springchain.bench("seed", quick=True, methods=["verlet"])
    assert result.records and {r.method for r in result.records} == {"verlet"}  # only the method asked for
    for r in result.records:  # each a Verlet run against the extended-precision reference
        assert 0 < r.error < 1 and r.force_evals == r.steps + 1 and abs(r.dt * r.steps - 100.0) < 1e-9


def _readme_python_example() -> str:
    text = README.read_text(encoding="utf-8")
    m = re.search(r"## Python API.*?```python\n(.*?)```", text, re.S)
    assert m, "README has a '## Python API' section with a python example"
    return m.group(1)


def test_readme_api_example_runs_as_written(tmp_path, monkeypatch, capsys):
    """The example as a user's script run from an empty folder: in this process (its imports and
    compiled kernels shared with the other tests; what a fresh interpreter loads is
    :func:`test_one_namespace_and_no_module_loaded_twice`'s), every file it names written."""
    code = compile(_readme_python_example(), "README.md (Python API example)", "exec")
    monkeypatch.chdir(tmp_path)
    exec(code, {"__name__": "__main__"})
    assert "5*k/(3*m)" in capsys.readouterr().out
    for name in ("seed.npz", "seed-positions.png", "springchain-out/seed-mode2.gif"):
        assert (tmp_path / name).stat().st_size > 0, name


def test_one_namespace_and_no_module_loaded_twice():
    code = ("import sys, springchain\n"
            "springchain.simulate('seed', steps=10)\n"
            "springchain.modes('seed')\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('derive', 'numeric', 'generated', 'scenes'))\n"
            "print(bad)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd="/")
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "[]"


def test_import_is_light_and_sets_no_backend():
    code = ("import sys, matplotlib\n"
            "before = matplotlib.get_backend()\n"
            "import springchain, springchain.cli\n"
            "heavy = [m for m in ('sympy', 'scipy', 'numba', 'matplotlib.pyplot') if m in sys.modules]\n"
            "import springchain.numeric.plots.figures, springchain.numeric.run.simulate\n"
            "print(heavy, matplotlib.get_backend() == before, 'matplotlib.pyplot' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd="/")
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "[] True False"


def test_method_name_table_matches_the_implementations():
    from springchain.numeric.run import registry
    from springchain.numeric.run.protocol import Kind

    names = registry.names()
    assert names[0] == registry.EXACT and springchain.method_names() == list(names)
    assert names == registry.names(Kind.EXACT) + registry.names(Kind.STEP) + registry.names(Kind.ADAPTIVE)
    for kind in (Kind.STEP, Kind.ADAPTIVE):  # every implementation calls itself by its registered name
        assert all(cls.name == name for name, cls in registry.classes(kind).items())


def test_stability_limits_are_computed_on_first_use_not_at_import():
    code = ("import springchain.numeric.integrators as I\n"
            "print('stability_limit' in I.KahanLi8.table.__dict__)\n"
            "I.KahanLi8.stability_limit\n"
            "print('stability_limit' in I.KahanLi8.table.__dict__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd="/")
    assert out.stdout.split() == ["False", "True"], out.stderr[-2000:]


def test_library_errors_name_the_quantity_and_the_command_adds_the_flag(tmp_path, capsys):
    with pytest.raises(springchain.RunRefused) as exc:
        springchain.simulate("seed", methods=["verlet"], dt=5.0)
    assert exc.value.quantity == "dt" and "--" not in str(exc.value)
    argv = ["simulate", "seed", "--method", "verlet", "--dt", "5", "--no-figures", "--out", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("springchain: error: --dt: dt = 5 is at or beyond verlet's stability limit"), err
    with pytest.raises(springchain.RunRefused) as exc:
        springchain.simulate("duffing", methods=["modal"])
    assert exc.value.quantity == "method" and str(exc.value).startswith("method 'modal'")


def test_generate_writes_and_checks_like_the_derive_command(tmp_path):
    from springchain._modules import generated_dir

    (checked,) = springchain.generate(["seed"], generated_dir(), check=True)  # the package's own module: fresh
    assert checked.fresh is True and checked.path.name == "seed.py" and checked.lines is None
    (written,) = springchain.generate(["seed"], out=tmp_path)
    assert written.path == tmp_path / "seed.py" and written.fresh is None
    assert written.lines == len(written.path.read_text(encoding="utf-8").splitlines())
    assert written.path.read_text(encoding="utf-8") == checked.path.read_text(encoding="utf-8")
    written.path.write_text("# stale\n", encoding="utf-8")
    (stale,) = springchain.generate(["seed"], out=tmp_path, check=True)
    assert stale.fresh is False and "stale" in stale.message


def test_chain_modes_report_is_computed_once_and_to_json_returns_a_copy(tmp_path, monkeypatch):
    """A damped [chain]'s ζ can take seconds: ``to_text`` and ``to_json`` of one result share one report,
    and editing the dict ``to_json`` returned does not change the next one."""
    from springchain import _api

    calls = []
    real = _api._chain_damped
    monkeypatch.setattr(_api, "_chain_damped", lambda *a: calls.append(1) or real(*a))
    text = ('name = "dc"\n[parameters]\nm = 1.0\nk = 2.0\n[chain]\nn = 4\nmass = "m"\nk = "k"\n'
            'left = "wall"\nright = "free"\n[[dampers]]\nbetween = [0, "wall"]\nc = "0.1"\n')
    path = tmp_path / "dc.toml"
    path.write_text(text)
    m = springchain.modes(path)
    data = m.to_json()
    assert "   zeta = " in m.to_text() and len(calls) == 1
    data["modes"].clear()
    assert len(m.to_json()["modes"]) == 4 and len(calls) == 1
