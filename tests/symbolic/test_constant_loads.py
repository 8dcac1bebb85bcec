"""The static equilibrium under every constant load (oracle findings N2, N11): cubic (k3) springs under
gravity or a constant force, and potentials under a constant ground acceleration or the constant part of a
harmonic force. References: the statics solved here by mpmath's findroot from the hand-written balance
(k d + k3 d^3 = the load the spring carries), the modes as mpmath's eigenvalues of K_t = k + 3 k3 d^2."""

from __future__ import annotations

import mpmath
import pytest

import springchain as sc
from springchain import SceneError

mpmath.mp.dps = 40


def _scene(tmp_path, name, body):
    path = tmp_path / f"{name}.toml"
    path.write_text(f'name = "{name}"\n' + body)
    return sc.load(str(path))


def _rel(a, b):
    return float(abs(mpmath.mpf(a) - b) / abs(b))


def _hung_pair_reference(m, k, kappa, load):
    """Wall -(k, kappa)- p -(k)- q, the same constant force ``load`` on each mass: the wall spring carries
    2 load (k d0 + kappa d0^3 = 2 load), the other one load (k d1 = load); x = (d0, d0 + d1)."""
    m, k, kappa, load = (mpmath.mpf(v) for v in (m, k, kappa, load))
    d0 = mpmath.findroot(lambda d: k * d + kappa * d**3 - 2 * load, 2 * load / k)
    d1 = load / k
    kt = k + 3 * kappa * d0**2
    K = mpmath.matrix([[kt + k, -k], [-k, k]]) / m
    return (d0, d0 + d1), sorted(mpmath.eigsy(K)[0])


CUBIC_PAIR = '''[parameters]
m = 1.0
k = 2.0
kappa = 0.5
{params}
[masses]
p = "m"
q = "m"
[[springs]]
between = ["wall", "p"]
k = "k"
k3 = "kappa"
[[springs]]
between = ["p", "q"]
k = "k"
{load}
'''


@pytest.mark.parametrize("params, load, per_mass", [
    ("g = -1.0", '[gravity]\ng = "g"', -1.0),                                   # N2: gravity
    ("F = 0.75", '[[forces]]\non = "p"\nf = "F"\n[[forces]]\non = "q"\nf = "F"', 0.75),  # constant forces
    ("A = 0.5", '[ground]\nacceleration = "A"', -0.5),                           # -m A on each mass
    ("F = 0.75", '[[forces]]\non = "p"\nf = "F + cos(3*t)"\n[[forces]]\non = "q"\nf = "F - 2*sin(t)"', 0.75),
])
def test_cubic_spring_under_constant_loads(tmp_path, params, load, per_mass):
    """x_eq solves the nonlinear statics and omega^2 are those of K_t about it (not K^-1 M g and the linear k)."""
    m = sc.modes(_scene(tmp_path, "cubic_load", CUBIC_PAIR.format(params=params, load=load)))
    x_ref, w2_ref = _hung_pair_reference(1.0, 2.0, 0.5, per_mass)
    js = m.to_json()
    x = [float(v) for v in js["equilibrium"]["x"]]
    assert max(_rel(a, b) for a, b in zip(x, x_ref)) < 1e-14, (x, x_ref)
    assert max(_rel(a, b) for a, b in zip(m.omega2_values, w2_ref)) < 1e-13, (m.omega2_values, w2_ref)
    springs = js["equilibrium"]["springs"]
    assert _rel(springs[0]["stiffness_value"], 2 + 3 * mpmath.mpf("0.5") * x_ref[0] ** 2) < 1e-14
    assert any("cubic springs under constant loads" in n for n in js["notes"]), js["notes"]
    assert not any("linearization about x = 0" in n for n in js["notes"]), js["notes"]


def test_cubic_spring_without_constant_load_stays_about_zero(tmp_path):
    """No constant load: the cubic spring is linearised about x = 0 as before (k, no equilibrium section)."""
    m = sc.modes(_scene(tmp_path, "cubic_free", CUBIC_PAIR.format(params="", load="")))
    K = mpmath.matrix([[4, -2], [-2, 2]])
    ref = sorted(mpmath.eigsy(K)[0])
    assert max(_rel(a, b) for a, b in zip(m.omega2_values, ref)) < 1e-14
    assert "equilibrium" not in m.to_json()


def test_potential_under_constant_ground_acceleration(tmp_path):
    """N11: k d + beta d^3 = -m A (the ground's constant acceleration is a static load, as gravity)."""
    m = sc.modes(_scene(tmp_path, "gpot", '''[parameters]
m = 1.0
k = 2.0
beta = 0.5
A = -1.0
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[ground]
acceleration = "A"
'''))
    d = mpmath.findroot(lambda d: 2 * d + d**3 / 2 - 1, 0.5)
    js = m.to_json()
    assert _rel(js["equilibrium"]["springs"][0]["extension_value"], d) < 1e-15  # d = x_p - 0, -m A = +1 stretches it
    assert _rel(m.omega2_values[0], 2 + mpmath.mpf(3) / 2 * d**2) < 1e-14


def test_sensitivity_of_a_loaded_cubic_scene_refused(tmp_path):
    """The modes' stiffness comes from a numeric equilibrium: derivatives in the parameters are refused in
    one line (they were those of the linear springs, about the wrong configuration)."""
    scene = _scene(tmp_path, "cubic_sens", CUBIC_PAIR.format(params="g = -1.0", load='[gravity]\ng = "g"'))
    with pytest.raises(SceneError, match="static equilibrium solved numerically"):
        sc.sensitivities(scene)
