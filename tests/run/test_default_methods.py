"""Default methods of ``simulate``: a Verlet that would be unstable at the run's dt gives way to
the exact method with a note (a stiff scene of the user's runs at once); asked for by name it
still refuses in one line."""

from __future__ import annotations

import numpy as np
import pytest

import springchain as sc
from springchain.cli import main

STIFF = """name = "stiff"
[parameters]
K = 1e9
w = 1.0
[masses]
a = "w"
x = "2*w"
[[springs]]
between = ["wall", "a"]
k = "K"
[[springs]]
between = ["a", "x"]
k = "w"
[initial]
x = [0.1, 0.0]
v = [0.0, 0.0]
[simulation]
dt = 0.1
steps = 50
"""


pytestmark = pytest.mark.usefixtures("fresh_cache")


def test_unstable_default_verlet_gives_way(tmp_path, capsys):
    path = tmp_path / "stiff.toml"
    path.write_text(STIFF)
    run = sc.simulate(path)
    assert list(run.x) == ["modal"]
    (note,) = run.summary["notes"]
    assert "verlet" in note and "stability limit" in note
    assert np.all(np.isfinite(run.x["modal"]))
    assert main(["simulate", str(path), "--out", str(tmp_path / "o"), "--no-figures"]) == 0
    assert "note: verlet not run by default" in capsys.readouterr().out


def test_stable_defaults_unchanged(tmp_path):
    path = tmp_path / "stiff.toml"
    path.write_text(STIFF.replace("dt = 0.1", "dt = 1e-10"))
    run = sc.simulate(path)
    assert list(run.x) == ["modal", "verlet"] and run.summary["notes"] == []


def test_unstable_verlet_by_name_is_refused(tmp_path, capsys, monkeypatch):
    # refused after loading the module (it needs ω_max): a loaded machine may show that phase's progress
    monkeypatch.setenv("SPRINGCHAIN_PROGRESS", "0")
    path = tmp_path / "stiff.toml"
    path.write_text(STIFF)
    status = main(["simulate", str(path), "--method", "verlet", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and "stability limit" in err[0], err
