"""Physical units in scenes (issue 37, item 1): values with units converted to SI once at load, checked
against what each key means, expressions checked for dimensional consistency, CSV headers with units,
one-line refusals, and plain numbers exactly as before without pint.

References are pint's own conversions (``ureg.Quantity(...).to(...)``) and the SI numbers written
by hand; nothing here compares springchain's conversion with itself.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import one_line_error, run_cli

from springchain.derive.errors import SceneError
from springchain.derive.scene import load_scene

ENGINEERING = '''
name = "storey"
[parameters]
m = "10 t"
k = "4 MN/m"
c = "2 kN*s/m"
F0 = "2 kN"
w = "3 rad/s"
x0 = "5 mm"
[masses]
m1 = "m"
m2 = "2*m"
[[springs]]
between = ["wall", "m1"]
k = "k"
[[springs]]
between = ["m1", "m2"]
k = "1.5 MN/m"
k3 = "20 kN/cm^3"
[[dampers]]
between = ["m1", "m2"]
c = "c"
[[forces]]
on = "m2"
f = "F0*cos(w*t)"
[gravity]
g = "9.81 m/s^2"
[initial]
x = ["2 mm", "5 mm"]
v = [0.0, "1 cm/s"]
[simulation]
dt = "10 ms"
steps = 50
'''


@pytest.fixture(scope="module")
def ureg():
    pint = pytest.importorskip("pint")
    return pint.UnitRegistry()


def test_values_with_units_are_si_by_pints_own_conversions(ureg):
    s = load_scene("eng.toml", ENGINEERING)
    si = lambda v, u, to: ureg.Quantity(v, u).to(to).magnitude  # noqa: E731
    assert s.parameters["m"] == pytest.approx(si(10, "t", "kg"), rel=1e-15)
    assert s.parameters["k"] == pytest.approx(si(4, "MN/m", "N/m"), rel=1e-15)
    assert s.parameters["c"] == pytest.approx(si(2, "kN*s/m", "N*s/m"), rel=1e-15)
    assert s.parameters["F0"] == pytest.approx(si(2, "kN", "N"), rel=1e-15)
    assert s.parameters["x0"] == pytest.approx(si(5, "mm", "m"), rel=1e-15)
    assert float(s.springs[1].k.value) == pytest.approx(si(1.5, "MN/m", "N/m"), rel=1e-15)
    assert float(s.springs[1].k3.value) == pytest.approx(si(20, "kN/cm^3", "N/m^3"), rel=1e-15)
    assert float(s.gravity.value) == pytest.approx(9.81, rel=1e-15)
    assert s.dt == pytest.approx(0.01, rel=1e-15)
    assert np.allclose(s.x0, [0.002, 0.005], rtol=1e-15) and np.allclose(s.v0, [0.0, 0.01], rtol=1e-15)


def test_a_scene_in_units_has_the_modes_of_the_same_scene_in_si():
    pytest.importorskip("pint")
    import springchain as sc

    eng = load_scene("eng.toml", ENGINEERING)
    si_text = (ENGINEERING.replace('"10 t"', "1e4").replace('"4 MN/m"', "4e6").replace('"2 kN*s/m"', "2e3")
               .replace('"2 kN"', "2e3").replace('"3 rad/s"', "3.0").replace('"5 mm"', "0.005")
               .replace('"1.5 MN/m"', '"1.5e6"').replace('"20 kN/cm^3"', '"2e10"').replace('"9.81 m/s^2"', '"9.81"')
               .replace('"2 mm"', "0.002").replace('"1 cm/s"', "0.01").replace('"10 ms"', "0.01"))
    si = load_scene("si.toml", si_text)
    assert eng.parameters.keys() == si.parameters.keys()
    for name, value in si.parameters.items():
        assert eng.parameters[name] == pytest.approx(value, rel=1e-16, abs=0)
    # converted once at load: the generated modules are the same code (no run-time cost, no other numbers)
    from springchain._modules import system_of

    code = [Path(system_of(s)[0].module.__file__).read_text().splitlines() for s in (eng, si)]
    body = [[ln for ln in c if "sha256" not in ln.lower() and "regenerate with" not in ln] for c in code]
    assert body[0] == body[1] and len(body[0]) > 100
    a = sc.frf(eng, "m1", "m2", transfer=False, points=50)
    b = sc.frf(si, "m1", "m2", transfer=False, points=50)
    assert np.array_equal(a.omega, b.omega) and np.allclose(a.H, b.H, rtol=1e-14, atol=0)


@pytest.mark.parametrize("old, new, key, given, expected", [
    ('k = "1.5 MN/m"', 'k = "4 kN"', "springs[1].k", "unit kN", "a stiffness, [mass]/[time]^2"),
    ('m = "10 t"', 'm = "10 kip"', "masses.m1", "a weight, not a mass", "a mass, [mass]"),
    ('k = "1.5 MN/m"', 'k = "m"', "springs[1].k", "[mass] (a mass)", "a stiffness"),
    ('c = "c"', 'c = "k"', "dampers[0].c", "(a stiffness)", "a damping coefficient, [mass]/[time]"),
    ('f = "F0*cos(w*t)"', 'f = "F0*cos(3*t)"', "forces[0].f", "argument of cos()", "plain number"),
    ('f = "F0*cos(w*t)"', 'f = "F0 + 1"', "forces[0].f", "adds a plain number to", "dimensionally consistent"),
    ('g = "9.81 m/s^2"', 'g = "9.81 m/s"', "gravity.g", "a velocity", "an acceleration"),
    ('dt = "10 ms"', 'dt = "10 mm"', "simulation.dt", "unit mm", "a time step, [time]"),
    ('x = ["2 mm", "5 mm"]', 'x = ["2 kg", "5 mm"]', "initial.x[0]", "unit kg", "a displacement"),
    ('k3 = "20 kN/cm^3"', 'k3 = "k"', "springs[1].k3", "(a stiffness)", "a cubic stiffness"),
])
def test_a_unit_of_the_wrong_dimension_is_refused_in_one_line(tmp_path, capsys, old, new, key, given, expected):
    pytest.importorskip("pint")
    assert old in ENGINEERING
    path = tmp_path / "eng.toml"
    path.write_text(ENGINEERING.replace(old, new, 1))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == key
    line = one_line_error(*run_cli(["modes", path], capsys), str(path), key, given, expected)
    assert "accepted:" in line


@pytest.mark.parametrize("old, new, key", [
    # a parameter in grams lands where an acceleration belongs: 0.3 g was meant as 0.3 standard gravity
    ('g = "9.81 m/s^2"', 'g = "a0"', "gravity.g"),
    # ... in a force, multiplied by a mass
    ('f = "F0*cos(w*t)"', 'f = "a0*m*cos(w*t)"', "forces[0].f"),
    # ... in a sum with an acceleration
    ('g = "9.81 m/s^2"', 'g = "a0 + a1"', "gravity.g"),
    # a value written "0.3 g" directly in a force slot
    ('f = "F0*cos(w*t)"', 'f = "0.3 g"', "forces[0].f"),
])
def test_a_value_in_grams_where_another_dimension_belongs_suggests_g_0(tmp_path, capsys, old, new, key):
    """pint's g is the gram: in a parameter (no slot to say otherwise) "0.3 g" is 0.3 gram (3e-4 kg, pint's
    own conversion), and where it lands in a slot of another dimension the refusal says that standard
    gravity is g_0. A bare g in an acceleration slot is standard gravity already and loads."""
    pytest.importorskip("pint")
    text = ENGINEERING.replace("[masses]", 'a0 = "0.3 g"\na1 = "1 m/s^2"\n[masses]', 1).replace(old, new, 1)
    path = tmp_path / "gram.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == key
    one_line_error(*run_cli(["modes", path], capsys), key, "g is the gram", "g_0", "'0.3 g_0'")
    fixed = load_scene("eng.toml", text.replace('a0 = "0.3 g"', 'a0 = "0.3 g_0"').replace('f = "0.3 g"', 'f = "F0"'))
    assert fixed.parameters["a0"] == pytest.approx(0.3 * 9.80665, rel=1e-15)
    assert load_scene("eng.toml", ENGINEERING.replace('"9.81 m/s^2"', '"1 g"')).parameters  # g there: gravity
    grams = load_scene("eng.toml", ENGINEERING.replace("[masses]", 'a0 = "0.3 g"\n[masses]', 1))
    assert grams.parameters["a0"] == pytest.approx(3e-4, rel=1e-15)  # a parameter alone: pint's gram


@pytest.mark.parametrize("unit, why", [
    ("MN/m^(10^10)", "a power that is not a small whole number"),
    ("m^99", "exponent beyond 16"),
    ("furlong/fortnightz", "unknown unit"),
    ("degC", "offset unit"),
    ("N\u00b7m", "character"),
    ("m;import os", "character"),
])
def test_hostile_or_unknown_units_are_refused_without_evaluating_them(unit, why):
    pytest.importorskip("pint")
    text = ENGINEERING.replace('k = "1.5 MN/m"', f'k = "4 {unit}"', 1)
    with pytest.raises(SceneError, match=why) as info:
        load_scene("eng.toml", text)
    assert info.value.key == "springs[1].k" and "\n" not in str(info.value)


def test_a_power_followed_by_a_product_is_a_unit(ureg):
    """``N^2*s`` (a force PSD per rad/s-like unit), ``kg*m^2*s^-2``: a power then ``*`` is a product, not a
    nested exponent (which stays refused); factors and dimensions against pint's own."""
    from springchain.derive.units import parse_unit

    for text in ("N^2*s", "kg*m^2*s^-2", "kN**2*ms", "(mm/s^2)^2/Hz"):
        u = parse_unit(text)
        ref = ureg.Quantity(1, text.replace("^", "**")).to_base_units()
        assert float(u.factor) == pytest.approx(ref.magnitude, rel=1e-15)
        assert dict(u.dimension.map) == {k: v for k, v in ref.dimensionality.items()}
    for text in ("m^2**3", "m^2^3", "m**2**3"):
        with pytest.raises(ValueError, match="not a small whole number"):
            parse_unit(text)


def test_potentials_are_energies_of_the_extension_in_metres():
    pytest.importorskip("pint")
    base = '''name = "p"
[parameters]
m = "1 kg"
k = "100 N/m"
b = B
[masses]
m1 = "m"
[[springs]]
between = ["wall", "m1"]
potential = "V"
'''
    ok = load_scene("p.toml", base.replace("B", '"1e6 N/m^3"').replace("V", "k*d**2/2 + b*d**4/4"))
    assert ok.parameters["b"] == 1e6
    with pytest.raises(SceneError, match=r"adds \[length\]\^4 to") as info:  # a plain b: dimensionless
        load_scene("p.toml", base.replace("B", "1e6").replace("V", "k*d**2/2 + b*d**4/4"))
    assert "plain-number parameter b" in str(info.value) and info.value.key == "springs[0].potential"


def test_csv_headers_with_units_are_converted_by_pint(tmp_path, ureg):
    (tmp_path / "rec.csv").write_text("t [ms], a [g]\n0, 0\n100, 0.5\n250, -0.25\n")
    (tmp_path / "f.csv").write_text("t [s], f [kN]\n0, 1\n1, 2\n")
    (tmp_path / "s.toml").write_text('''name = "s"
[parameters]
m = "1 t"
[masses]
m1 = "m"
[[springs]]
between = ["wall", "m1"]
k = "1e5"
[[forces]]
on = "m1"
table = "f.csv"
[ground]
table = "rec.csv"
''')
    s = load_scene(tmp_path / "s.toml")
    t_ref = ureg.Quantity(np.array([0, 100, 250.0]), "ms").to("s").magnitude
    a_ref = ureg.Quantity(np.array([0, 0.5, -0.25]), "standard_gravity").to("m/s^2").magnitude
    assert np.allclose(s.ground.table.t, t_ref, rtol=1e-15) and np.allclose(s.ground.table.y, a_ref, rtol=1e-15)
    assert np.allclose(s.table_forces[0].table.y, [1000.0, 2000.0], rtol=1e-15)


def test_csv_header_of_the_wrong_dimension_is_refused(tmp_path, capsys):
    pytest.importorskip("pint")
    (tmp_path / "rec.csv").write_text("t [s], a [kg]\n0, 0\n1, 1\n")
    (tmp_path / "s.toml").write_text('name = "s"\n[parameters]\n[masses]\nm1 = 1.0\n[[springs]]\n'
                                     'between = ["wall", "m1"]\nk = 1.0\n[ground]\ntable = "rec.csv"\n')
    one_line_error(*run_cli(["modes", tmp_path / "s.toml"], capsys), "ground.table", "column a [kg]",
                   "expected an acceleration")


def test_with_parameters_keeps_a_parameters_unit():
    pytest.importorskip("pint")
    s = load_scene("eng.toml", ENGINEERING).with_parameters(m=2e4, w=5.0)
    assert s.parameters["m"] == 2e4 and s.parameters["w"] == 5.0
    assert s.source["parameters"]["m"] == "20000.0 kg"  # still a mass: "m*g"-like expressions keep their check
    with pytest.raises(SceneError, match="a mass"):  # the new value is SI and still a mass: m2 = k would fail
        load_scene("eng.toml", ENGINEERING.replace('m2 = "2*m"', 'm2 = "2*k"'))


def test_without_pint_plain_numbers_work_and_a_unit_says_what_to_install(monkeypatch, tmp_path, capsys):
    from springchain.derive.units import registry

    registry.registry.cache_clear()
    monkeypatch.setitem(sys.modules, "pint", None)  # import pint fails
    try:
        plain = load_scene("plain.toml", 'name = "p"\n[parameters]\nm = 2.0\n[masses]\nm1 = "m"\n'
                                         '[[springs]]\nbetween = ["wall", "m1"]\nk = 8.0\n')
        assert plain.parameters == {"m": 2.0}
        path = tmp_path / "eng.toml"
        path.write_text(ENGINEERING)
        one_line_error(*run_cli(["modes", path], capsys), "parameters.F0", "needs pint",
                       'pip install "springchain[units]"')
    finally:
        registry.registry.cache_clear()


def test_a_scene_without_units_never_imports_pint():
    import subprocess

    code = ("import sys, springchain as sc; sc.load('seed'); sc.load('building_quake'); "
            "print('pint' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_xarray_outputs_carry_units_pint_xarray_reads(tmp_path):
    """Every variable of Simulation.to_xarray() (springs and modal energies included) quantifies with
    pint-xarray, each in the dimension its quantity has."""
    pytest.importorskip("pint_xarray")
    import springchain as sc

    run = sc.simulate("building_quake", steps=200, figures=False, out=tmp_path, springs=True, modal_energy=True)
    q = run.to_xarray().pint.quantify()
    want = {"x": "[length]", "v": "[length] / [time]", "aabs": "[length] / [time] ** 2", "drift": "[length]",
            "spring_force": "[length] * [mass] / [time] ** 2", "base_shear": "[length] * [mass] / [time] ** 2",
            "modal_energy": "[length] ** 2 * [mass] / [time] ** 2"}
    seen = set()
    for name in q.data_vars:
        quantity = next(k for k in sorted(want, key=len, reverse=True) if name.startswith(k + "_"))
        assert q[name].data.dimensionality == q[name].data._REGISTRY.parse_units(
            {"[length]": "m", "[length] / [time]": "m/s", "[length] / [time] ** 2": "m/s^2",
             "[length] * [mass] / [time] ** 2": "N", "[length] ** 2 * [mass] / [time] ** 2": "J"}[want[quantity]]
        ).dimensionality, name
        seen.add(quantity)
    assert seen == set(want) and str(q["time"].data.units) == "second"
    assert q["base_shear_modal"].dims == ("time",) and q["spring_force_modal"].dims == ("time", "spring")
