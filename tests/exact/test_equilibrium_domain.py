"""Static equilibria of spring potentials over the accepted domain (issue 31), against the extended-precision
reference of :mod:`equilibrium_reference` (SymPy's own parse of the potentials, mpmath at 50 digits,
the loads applied gradually from rest, Newton at every load step, Cholesky for stability).

Regressions of the issue: Lennard-Jones springs under gravity or a constant force were refused ("no
static equilibrium found": the float64 Newton never met its stopping rule at the rounding floor of the
LJ gradient), a pre-stressed scene without ``[initial]`` was told "its motion is zero" although it
starts away from its equilibrium, and ``rsa`` on a potential scene said "linearisation about x = 0".

Then a hypothesis search: 1–5 masses hanging from a wall or between two walls, springs of every
potential family the README names (FPUT-α/β, Toda, Morse, Lennard-Jones, exp, log, FENE, cosh forms,
pre-stressed, linear), gravity or constant forces, values log-uniform over ±6 decades (±12 in the slow
run). Property: the reported x_eq (4e-16 relative), each spring's V''(d) (1e-15) and ω² (1e-13) against
the reference, or a one-line refusal where the reference has no stable equilibrium on the loading path
(the fraction of the loads reached within 1e-5 of the reference's) — never a traceback, never a wrong
number; a refusal where the reference has an equilibrium must name float64's limit. The normal run draws
40 derandomized scenes plus every scene the generator found a failure with (tests/regressions/equilibrium/,
each saying what it found); the ``slow`` variant 400 × ``SPRINGCHAIN_SLOW_BUDGET`` (100 at the default).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from equilibrium_reference import reference
from helpers import SLOW_BUDGET as BUDGET
from helpers import run_cli

#: x_eq is correctly rounded (refined in mpmath): a few ulps of each coordinate, or of the largest where
#: a coordinate is much smaller than the others.
X_RTOL = 4e-16
X_FLOOR = 1e-30
#: ω² from an mpmath eigensolver on K rounded to 17 digits: 1e-13 relative, as the modes tests.
W_RTOL = 1e-13
#: Progress notes a derivation slower than a second prints on a loaded machine (not part of the error).
PROGRESS = re.compile(r"^springchain: (deriving|loading|reading|compiling)")

LJ = "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"
MORSE = "D*(1 - exp(-w*d))**2"


def hanging(name: str, params: dict, potentials: list[str], *, masses: list[str] | None = None,
            gravity: str | None = None, forces: dict | None = None, right_wall: bool = False,
            extra: str = "") -> str:
    """A chain of len(potentials) − right_wall masses hung from a wall (and tied to a second one)."""
    n = len(potentials) - int(right_wall)
    masses = masses or ["m"] * n
    ends = ["wall"] + [f"p{i}" for i in range(n)] + (["wall"] if right_wall else [])
    lines = [f'name = "{name}"', "[parameters]", *[f"{k} = {float(v)!r}" for k, v in params.items()], "[masses]",
             *[f'p{i} = "{m}"' for i, m in enumerate(masses)]]
    for s, pot in enumerate(potentials):
        lines += ["[[springs]]", f'between = ["{ends[s]}", "{ends[s + 1]}"]', f'potential = "{pot}"']
    if gravity is not None:
        lines += ["[gravity]", f'g = "{gravity}"']
    for on, f in (forces or {}).items():
        lines += ["[[forces]]", f'on = "p{on}"', f'f = "{f}"']
    return "\n".join(lines) + "\n" + extra


def _modes_json(path, capsys):
    status, out, err = run_cli(["modes", path, "--json"], capsys)
    return status, out, err


def _one_line(status, err: str, *parts) -> str:
    assert status == 2, err
    lines = [ln for ln in err.splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("springchain: error: "), err
    assert "Traceback" not in err
    for p in parts:
        assert p in lines[0], (p, lines[0])
    return lines[0]


def check_against_reference(data: dict, ref) -> float:
    """x_eq, each spring's V''(d) and ω² of ``modes --json`` against the reference; returns the worst
    error relative to its bound (≤ 1 passes)."""
    eq = data["equilibrium"]
    x = np.array(eq["x_value"])
    xr = [float(v) for v in ref.x]
    top = max(max(abs(v) for v in xr), X_FLOOR)
    worst = 0.0
    for xi, ri in zip(x, ref.x):
        err = abs(mpmath.mpf(float(xi)) - ri)
        worst = max(worst, float(err / max(X_RTOL * abs(ri), X_RTOL * 1e-3 * top, mpmath.mpf(X_FLOOR))))
    for s, kr in zip(eq["springs"], ref.stiffness):  # below float64's normal range: its rounding
        worst = max(worst, float(abs(mpmath.mpf(s["stiffness_value"]) - kr) / max(1e-15 * abs(kr), 1e-300)))
    w2 = sorted(m["omega2_value"] for m in data["modes"])
    for wi, wr in zip(w2, ref.omega2):
        worst = max(worst, float(abs(mpmath.mpf(wi) - wr) / (W_RTOL * abs(wr))))
    assert "stable" in eq["how"], eq["how"]
    return worst


# -- issue 31: Lennard-Jones under a constant load ------------------------------------------------------------
LJ_PARAMS = {"eps": 0.05, "r0": 1.12, "m": 0.3, "g": 0.1}


@pytest.mark.parametrize("load", ["gravity", "force"])
@pytest.mark.parametrize("family", ["lennard-jones", "morse"])
def test_two_atoms_hanging_under_a_constant_load(load, family, tmp_path, capsys):
    params = dict(LJ_PARAMS) if family == "lennard-jones" else {"D": 0.2, "w": 1.3, "m": 0.3, "g": 0.1}
    pot = LJ if family == "lennard-jones" else MORSE
    text = (hanging("atoms", params, [pot, pot], gravity="g") if load == "gravity"
            else hanging("atoms", params, [pot, pot], forces={0: "m*g", 1: "m*g"}))
    path = tmp_path / "atoms.toml"
    path.write_text(text)
    status, out, err = _modes_json(path, capsys)
    assert status == 0, err
    data = json.loads(out)
    ref = reference(text)
    assert ref.stable and ref.margin > 0.1
    assert check_against_reference(data, ref) <= 1.0
    if family == "lennard-jones":  # the numbers
        assert np.allclose(data["equilibrium"]["x_value"], [0.026770, 0.038421], rtol=0, atol=5e-7)
        assert np.allclose(sorted(m["omega2_value"] for m in data["modes"]), [2.3211, 18.6456], rtol=0, atol=5e-5)


def test_lennard_jones_beyond_its_largest_force_is_refused_naming_the_fraction(tmp_path, capsys):
    text = hanging("atoms", {**LJ_PARAMS, "g": 10.0}, [LJ, LJ], gravity="g")
    path = tmp_path / "atoms.toml"
    path.write_text(text)
    ref = reference(text)
    assert not ref.stable and 0.01 < ref.reached < 0.03
    for command in (["modes"], ["derive", "--out", tmp_path / "gen"]):
        status, _, err = run_cli([command[0], path, *command[1:]], capsys)
        line = _one_line(status, err, str(path), "springs[0].potential", "no static equilibrium found",
                         "a stable equilibrium exists only up to")
        assert abs(reached_fraction(line) - float(ref.reached)) <= 1e-5 * float(ref.reached)


# every potential family of the README, hung under gravity (three masses, the middle one twice as heavy)
FAMILIES = {
    "fput-alpha": ("k*d**2/2 + alpha*d**3/3", {"k": 2.0, "alpha": 0.7}),
    "fput-alpha-softening": ("k*d**2/2 + alpha*d**3/3", {"k": 2.0, "alpha": -0.7}),
    "fput-beta": ("k*d**2/2 + beta*d**4/4", {"k": 2.0, "beta": 0.5}),
    "toda": ("a/b*exp(-b*d) + a*d", {"a": 3.0, "b": 0.8}),
    "morse": (MORSE, {"D": 3.0, "w": 0.7}),
    "lennard-jones": (LJ, {"eps": 2.0, "r0": 1.12}),
    "exp": ("c*(exp(q*d) - q*d)", {"c": 1.5, "q": 0.9}),
    "log": ("c*(d - r*log(1 + d/r))", {"c": 4.0, "r": 0.5}),
    "fene": ("-c*r**2*log(1 - (d/r)**2)/2", {"c": 3.0, "r": 0.6}),
    "cosh": ("c*cosh(q*d)", {"c": 2.0, "q": 1.1}),
    "pre-stressed": ("k*d**2/2 + T*d + d**4", {"k": 2.0, "T": 0.25}),
}


@pytest.mark.parametrize("family", sorted(FAMILIES))
@pytest.mark.parametrize("layout", ["hanging", "between-walls"])
def test_every_potential_family_under_gravity(family, layout, tmp_path, capsys):
    pot, params = FAMILIES[family]
    params = {**params, "m": 0.4, "g": 0.6}
    text = hanging(family.replace("-", "_"), params, [pot] * (3 + (layout == "between-walls")), masses=["m", "2*m", "m"],
                   gravity="g", right_wall=layout == "between-walls")
    path = tmp_path / "fam.toml"
    path.write_text(text)
    ref = reference(text)
    assert ref.stable and ref.margin > 1e-3, (ref.reached, ref.margin)
    status, out, err = _modes_json(path, capsys)
    assert status == 0, err
    assert check_against_reference(json.loads(out), ref) <= 1.0


# -- issue 31: a pre-stressed scene starts away from its equilibrium ------------------------------------------
PRE = hanging("pre", {"k": 2.0, "T": 0.5, "m": 1.0}, ["k*d**2/2 + T*d + d**4", "k*d**2/2 + T*d"],
              extra="[simulation]\ndt = 0.001\nsteps = 200\n")


def test_prestressed_scene_without_initial_moves(tmp_path):
    """Released at rest at x = 0, which is not its equilibrium: x(t) = a0 t²/2 + O(t⁴) with
    a0 = −∇U(0)/m from the potentials' V'(0) (here −T + T = 0 on p0 and −T on p1)."""
    import springchain

    path = tmp_path / "pre.toml"
    path.write_text(PRE)
    ref = reference(PRE)
    assert ref.stable and max(abs(float(v)) for v in ref.x) > 0.2
    run = springchain.simulate(path, methods=["verlet"], progress=False)
    t, x = np.asarray(run.t), np.asarray(run.x["verlet"])
    a0 = np.array([0.0, -0.5])  # −∇U(0)/m: the tensions at rest, T on both sides of p0, T pulling p1 back
    early = t <= 0.02
    # Taylor: x = a0 t²/2 + (jerk terms vanish at rest) + O(t⁴); Verlet's error O(dt² t²)
    assert np.allclose(x[early], 0.5 * a0[None, :] * t[early, None] ** 2, rtol=0, atol=1e-7)
    assert np.max(np.abs(x[-1])) > 1e-3


def test_balanced_prestress_without_initial_is_still_refused(tmp_path, capsys):
    """Between two walls with the same pre-stress on both springs x = 0 is the equilibrium: nothing moves."""
    text = hanging("balanced", {"k": 2.0, "T": 0.5, "m": 1.0}, ["k*d**2/2 + T*d + d**4", "k*d**2/2 + T*d + d**4"],
                   right_wall=True)
    path = tmp_path / "balanced.toml"
    path.write_text(text)
    ref = reference(text)
    assert all(v == 0 for v in ref.x)
    status, out, err = run_cli(["simulate", path, "--method", "verlet"], capsys)
    _one_line(status, err, "initial: missing", "its motion is zero")


# -- issue 31: rsa says what it linearises about ----------------------------------------------------------------
def test_rsa_of_a_potential_scene_names_its_equilibrium(tmp_path, capsys):
    path = tmp_path / "pre.toml"
    path.write_text(PRE)
    spec = tmp_path / "flat.csv"
    spec.write_text("T,Sa\n0.01,1.0\n10,1.0\n")
    status, out, err = run_cli(["rsa", path, "--spectrum", spec, "--json"], capsys)
    assert status == 0, err
    notes = json.loads(out)["notes"]
    ref = reference(PRE)
    [note] = [n for n in notes if "potential" in n]
    assert "x = 0" not in note and "static equilibrium" in note
    shown = [float(v) for v in re.search(r"x_eq = \(([^)]*)\)", note).group(1).split(",")]
    assert np.allclose(shown, [float(v) for v in ref.x], rtol=1e-9, atol=0)


# -- hypothesis: every potential family, every load, values across many decades --------------------------------
#: Potential families (the README's and the exp/log/cosh forms), ``{i}`` the spring's index in its
#: parameters' names, and each parameter's kind: "pos" (log-uniform > 0), "signed" (either sign),
#: "length" (a rest length or range, log-uniform over fewer decades).
GEN_FAMILIES = {
    "fput_alpha": ("k{i}*d**2/2 + a{i}*d**3/3", {"k": "pos", "a": "signed"}),
    "fput_beta": ("k{i}*d**2/2 + b{i}*d**4/4", {"k": "pos", "b": "pos"}),
    "toda": ("a{i}/b{i}*exp(-b{i}*d) + a{i}*d", {"a": "pos", "b": "pos"}),
    "morse": ("D{i}*(1 - exp(-w{i}*d))**2", {"D": "pos", "w": "pos"}),
    "lj": ("e{i}*((r{i}/(r{i} + d))**12 - 2*(r{i}/(r{i} + d))**6)", {"e": "pos", "r": "length"}),
    "exp": ("c{i}*(exp(q{i}*d) - q{i}*d)", {"c": "pos", "q": "signed"}),
    "log": ("c{i}*(d - r{i}*log(1 + d/r{i}))", {"c": "pos", "r": "length"}),
    "fene": ("-c{i}*r{i}**2*log(1 - (d/r{i})**2)/2", {"c": "pos", "r": "length"}),
    "cosh": ("c{i}*cosh(q{i}*d)", {"c": "pos", "q": "pos"}),
    "prestressed": ("k{i}*d**2/2 + T{i}*d + b{i}*d**4/4", {"k": "pos", "T": "signed", "b": "pos"}),
    "linear": ("k{i}*d**2/2", {"k": "pos"}),
}


@st.composite
def _value(draw, kind: str, decades: int) -> float:
    span = 2 if kind == "length" else decades
    mag = 10.0 ** draw(st.floats(-span, span, allow_nan=False))
    mag = float(f"{mag:.6g}")  # short decimal TOML literals
    if kind == "signed" and draw(st.booleans()):
        return -mag
    return mag


@st.composite
def equilibrium_scenes(draw, decades: int = 6) -> str:
    """TOML text: 1–5 masses hung from a wall (free end) or between two walls, one potential family per
    spring, gravity (either sign) or constant forces, values log-uniform over 2·decades decades."""
    n = draw(st.integers(1, 5))
    walls = draw(st.booleans())
    params, pots = {}, []
    for i in range(n + int(walls)):
        fam = draw(st.sampled_from(sorted(GEN_FAMILIES)))
        text, kinds = GEN_FAMILIES[fam]
        for p, kind in kinds.items():
            params[f"{p}{i}"] = draw(_value(kind, decades))
        pots.append(text.format(i=i))
    masses = []
    for i in range(n):
        params[f"m{i}"] = draw(_value("pos", decades))
        masses.append(f"m{i}")
    if draw(st.booleans()):
        params["g"] = draw(_value("signed", decades))
        return hanging("gen", params, pots, masses=masses, gravity="g", right_wall=walls)
    forces = {}
    for i in sorted(draw(st.sets(st.integers(0, n - 1), min_size=1, max_size=n))):
        params[f"f{i}"] = draw(_value("signed", decades))
        forces[i] = f"f{i}"
    return hanging("gen", params, pots, masses=masses, forces=forces, right_wall=walls)


# -- the generator's findings (tests/regressions/equilibrium/*.toml, each saying what it found) ------------------
FOUND = {p.stem: p.read_text() for p in sorted((Path(__file__).resolve().parents[1] / "regressions" / "equilibrium").glob("*.toml"))}


def with_found_examples(test):
    """``@example`` for every scene the generator found a failure with."""
    for text in FOUND.values():
        test = example(text=text)(test)
    return test


#: Decidedness below which the reference's verdict is too close to its edge for float64 to be held to it.
MARGIN = 1e-8


def check_scene(text: str, tmp_path, capsys) -> str:
    """The property; returns the outcome ("accepted", "refused", "undecided") for the statistics."""
    path = tmp_path / "gen.toml"
    path.write_text(text)
    status, out, err = _modes_json(path, capsys)
    assert "Traceback" not in err
    ref = reference(text)
    clear = ref.margin > MARGIN
    if status == 0:
        data = json.loads(out)
        if ref.x is None or not ref.stable:
            assert not clear, f"an equilibrium was reported where the reference has no stable one:\n{text}"
            return "undecided"
        assert check_against_reference(data, ref) <= 1.0, text
        return "accepted"
    line = _one_line(status, err)
    if ref.stable and clear:
        assert "float64" in line, f"refused although the reference has a stable equilibrium:\n{line}\n{text}"
        return "refused"
    if ref.x is None and clear and "only up to" in line:  # the fraction of the loads the path reaches
        assert abs(reached_fraction(line) - float(ref.reached)) <= 1e-5 * max(float(ref.reached), 1e-3), \
            (line, ref.reached)
    return "refused"


def reached_fraction(line: str) -> float:
    """The fraction of the loads a refusal says the path reached (``0.0200141`` or ``1 - 2.3e-05``)."""
    m = re.search(r"only up to (1 - )?([0-9.e+-]+) of them", line)
    return 1.0 - float(m.group(2)) if m.group(1) else float(m.group(2))


_SETTINGS = dict(deadline=None, derandomize=True,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@settings(max_examples=40, **_SETTINGS)
@given(text=equilibrium_scenes())
@with_found_examples
def test_generated_equilibria_against_the_reference(text, tmp_path, capsys):
    event(check_scene(text, tmp_path, capsys))


@pytest.mark.slow
@settings(max_examples=int(400 * BUDGET), **_SETTINGS)
@given(text=equilibrium_scenes(decades=12))
@with_found_examples
def test_generated_equilibria_against_the_reference_wide(text, tmp_path, capsys):
    event(check_scene(text, tmp_path, capsys))


def test_prestressed_free_piece_keeps_its_centre_of_mass(tmp_path, capsys):
    """A free piece (no wall) with pre-stressed springs: each extension solves V'(d) = 0 (no load beyond
    any spring), the centre of mass stays at 0. Reference: SymPy's nsolve on each V' at 40 digits."""
    text = ('name = "freep"\n[parameters]\nk = 2.0\nT = 0.5\n[masses]\na = "1"\nb = "3"\nc = "1"\n'
            '[[springs]]\nbetween = ["a", "b"]\npotential = "k*d**2/2 + T*d + d**4"\n'
            '[[springs]]\nbetween = ["b", "c"]\npotential = "k*(d - 1)**2/2 + d**4/4"\n')
    path = tmp_path / "freep.toml"
    path.write_text(text)
    status, out, err = _modes_json(path, capsys)
    assert status == 0, err
    import sympy as sp

    d = sp.Symbol("d")
    r1 = sp.nsolve(sp.diff(d**2 + d / 2 + d**4, d), d, -0.2, prec=40)
    r2 = sp.nsolve(sp.diff((d - 1) ** 2 + d**4 / 4, d), d, 0.7, prec=40)
    xa = -(3 * r1 + (r1 + r2)) / 5  # masses 1, 3, 1: centre of mass at 0
    ref = [xa, xa + r1, xa + r1 + r2]
    x = json.loads(out)["equilibrium"]["x_value"]
    assert all(abs(float(xi) - float(ri)) <= 4e-16 * abs(float(ri)) for xi, ri in zip(x, ref)), (x, ref)
