"""A damped rigid mode alone: one free mass slowed by a dashpot to the wall (or by Rayleigh α·M).

Every eigenvalue of its state matrix is real (λ = 0 and −c/m), so LAPACK returns real arrays; the
exact method refines them in extended precision and stored complex values into them (a TypeError,
oracle finding N17). The reference is the hand formula ``x = v0 m/c (1 − exp(−c t/m))``,
``v = v0 exp(−c t/m)``.
"""

from __future__ import annotations

import numpy as np
import pytest

import springchain as sc
from helpers import write_scene

DASHPOT = '''name = "dm1"
[parameters]
m = 2.0
c = 1.0
[masses]
p = "m"
[[dampers]]
between = ["p", "wall"]
c = "c"
[initial]
x = [0.3]
v = [1.0]
[simulation]
dt = 0.1
steps = 300
'''

RAYLEIGH = DASHPOT.replace('[[dampers]]\nbetween = ["p", "wall"]\nc = "c"\n', '[damping]\nrayleigh = [0.5, 0.0]\n')


@pytest.mark.parametrize("text", [DASHPOT, RAYLEIGH], ids=["dashpot", "rayleigh"])
def test_free_mass_with_a_dashpot_follows_the_hand_formula(tmp_path, text):
    path = write_scene(tmp_path, "dm1", text)
    run = sc.simulate(str(path), methods=["modal"], out=tmp_path / "out", progress=False)
    t = np.asarray(run.t)
    rate = 1.0 / 2.0  # c/m (and α for Rayleigh)
    x_ref = 0.3 + 1.0 / rate * -np.expm1(-rate * t)
    v_ref = np.exp(-rate * t)
    assert np.max(np.abs(run.x["modal"][:, 0] - x_ref)) <= 1e-13 * np.max(np.abs(x_ref))
    assert np.max(np.abs(run.v["modal"][:, 0] - v_ref)) <= 1e-13
