"""A cubic (k3) ``[chain]`` under a constant load: its linear outputs would be those about x = 0 while the
load moves the equilibrium (a silently wrong ω², H, rsa), so they are refused in one line naming the
load; its simulation (the equations of motion hold the load) runs; a load with zero mean keeps the modes,
which are then the hand formula's."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import one_line_error, run_cli

import springchain as sc

BASE = """name = "cubic_chain"
[parameters]
m = 1.0
k = 1.0
k3 = 0.5
g = 1.0
[chain]
n = 3
mass = "m"
k = "k"
k3 = "k3"
left = "wall"
right = "free"
"""
LOADS = {"gravity": '[gravity]\ng = "g"\n',
         "forces[0]": '[[forces]]\non = 2\nf = "0.5 + 0.5*sin(2*t)"\n'}


@pytest.mark.parametrize("key", sorted(LOADS))
def test_linear_outputs_refused_in_one_line(tmp_path, capsys, key):
    path = tmp_path / "c.toml"
    path.write_text(BASE + LOADS[key] + "[initial]\nx = [0.1, 0.0, 0.0]\n[simulation]\ndt = 0.01\nsteps = 20\n")
    for argv in (["modes", path], ["frf", path, "--input", "0", "--output", "2"]):
        status, out, err = run_cli(argv, capsys)
        one_line_error(status, out, err, key, "cubic (k3) springs", "equilibrium")
    for call in (lambda: sc.modes(path), lambda: sc.frf(path, input=0, output=2)):
        with pytest.raises(sc.SceneError, match="cubic"):
            call()
    run = sc.simulate(path, methods=["verlet"], out=tmp_path / "out")  # the motion itself is fine
    assert np.all(np.isfinite(run.x["verlet"]))


def test_a_load_with_zero_mean_keeps_the_modes(tmp_path):
    """cos(t)·sin(t) has mean 0: the equilibrium stays at 0, the modes are those of the linear chain,
    ω_j² = 4k/m sin²((2j−1)π/(4n+2)) (wall–free)."""
    path = tmp_path / "c.toml"
    path.write_text(BASE + '[[forces]]\non = 2\nf = "cos(t)*sin(t)"\n')
    got = sorted(float(m["omega2_value"]) for m in sc.modes(path).to_json()["modes"])
    want = [4 * math.sin((2 * j - 1) * math.pi / 14) ** 2 for j in (1, 2, 3)]
    assert np.allclose(got, want, rtol=1e-14, atol=0)
