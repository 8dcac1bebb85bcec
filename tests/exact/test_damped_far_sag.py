"""A damped scene released far from its equilibrium on a slow mode (oracle finding N16): the exact method
about a sag of 1e161 m must still give the centimetres the mass moves. Reference: the damped SDOF
m x'' + c x' + k x = m g in closed form, evaluated by mpmath at 250 digits from the scene's numbers."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

import springchain as sc

SCENE = '''name = "sag2"
[parameters]
m = {m!r}
k = {k!r}
g = -10.0
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
[damping]
modal = {zeta!r}
[gravity]
g = "g"
[initial]
x = [0.04]
v = [0.3]
[simulation]
dt = 0.01
steps = 40
record_every = 10
'''


def _reference(m, k, zeta, g, x0, v0, t):
    """x(t), v(t) of the underdamped oscillator about x_eq = m g / k (mpmath at 250 digits)."""
    with mpmath.workdps(250):
        m, k, zeta, g, x0, v0, t = (mpmath.mpf(v) for v in (m, k, zeta, g, x0, v0, t))
        w = mpmath.sqrt(k / m)
        wd = w * mpmath.sqrt(1 - zeta**2)
        xe = m * g / k
        y0 = x0 - xe
        e = mpmath.exp(-zeta * w * t)
        b = (v0 + zeta * w * y0) / wd
        y = e * (y0 * mpmath.cos(wd * t) + b * mpmath.sin(wd * t))
        dy = e * ((b * wd - zeta * w * y0) * mpmath.cos(wd * t) - (y0 * wd + zeta * w * b) * mpmath.sin(wd * t))
        return float(xe + y), float(dy)


@pytest.mark.parametrize("m, k, zeta", [(1e60, 1e-100, 0.2), (1e30, 1e-30, 0.05), (1.0, 1e-20, 0.5)])
def test_damped_exact_far_from_its_sag(tmp_path, m, k, zeta):
    path = tmp_path / "sag2.toml"
    path.write_text(SCENE.format(m=m, k=k, zeta=zeta))
    run = sc.simulate(sc.load(str(path)), methods=["modal"], progress=False, out=tmp_path / "out")
    ref = np.array([_reference(m, k, zeta, -10.0, 0.04, 0.3, t) for t in run.t])
    x, v = run.x["modal"][:, 0], run.v["modal"][:, 0]
    amp_x, amp_v = np.max(np.abs(ref[:, 0])), np.max(np.abs(ref[:, 1]))
    assert np.max(np.abs(x - ref[:, 0])) <= 1e-12 * amp_x, (x, ref[:, 0])
    assert np.max(np.abs(v - ref[:, 1])) <= 1e-12 * amp_v, (v, ref[:, 1])
