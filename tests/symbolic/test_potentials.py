"""Spring potentials (issue 21), the derive side: scene language, refusals, exact symbolic results,
the static equilibrium, and the generated forces against the SymPy derivative in 60-digit arithmetic.

References are built here from the TOML text the test writes: potentials are parsed with SymPy's
own ``parse_expr`` (trusted test text, never the package's parser), differentiated by SymPy and
evaluated by mpmath; equilibria and Hessians are checked through that independent route.
"""

from __future__ import annotations

import json
import re

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from sympy.parsing.sympy_parser import parse_expr

from helpers import run_cli

#: Progress notes a derivation slower than a second prints on a loaded machine (not part of the error).
PROGRESS = re.compile(r"^springchain: (deriving|loading|reading|compiling)")


def one_line_error(status, err, *parts):
    """Exit 2 and exactly one error line (progress notes of a slow derivation aside; otherwise as
    helpers.one_line_error)."""
    assert status == 2, err
    lines = [ln for ln in err.splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("springchain: error: "), err
    assert "Traceback" not in err
    for p in parts:
        assert p in lines[0], (p, lines[0])
    return lines[0]


def masses_toml(name, params, masses, springs, extra=""):
    """``springs``: (end, end, potential) triples."""
    lines = [f'name = "{name}"', "[parameters]", *[f"{k} = {float(v)!r}" for k, v in params.items()], "[masses]",
             *[f'{k} = "{v}"' for k, v in masses.items()]]
    for a, b, pot in springs:
        lines += ["[[springs]]", f'between = ["{a}", "{b}"]', f'potential = "{pot}"']
    return "\n".join(lines) + "\n" + extra


def chain_text(name, params, n, potential, left="wall", right="wall", extra=""):
    return "\n".join([f'name = "{name}"', "[parameters]", *[f"{k} = {float(v)!r}" for k, v in params.items()],
                      "[chain]", f"n = {n}", 'mass = "m"', f'potential = "{potential}"', f'left = "{left}"',
                      f'right = "{right}"', extra, ""])


# -- refusals: one line, exit 2, the key named ----------------------------------------------------------
REFUSED = {
    "no_d": (masses_toml("no_d", {"k": 1}, {"p": "1"}, [("wall", "p", "k")]),
             ("springs[0].potential", "does not depend on the extension d")),
    "singular": (masses_toml("singular", {"e": 1, "r": 1}, {"p": "1"}, [("wall", "p", "e*((r/d)**12 - 2*(r/d)**6)")]),
                 ("springs[0].potential", "not finite at the rest configuration")),
    "negative": (masses_toml("negative", {"k": 1}, {"p": "1", "q": "1"},
                             [("wall", "p", "k*d**2/2"), ("p", "q", "-k*d**2/2 + d**4")]),
                 ("springs[1].potential", "stiffness V''(d) = -1", "not positive")),
    "kink": (masses_toml("kink", {"k": 1}, {"p": "1"}, [("wall", "p", "k*sqrt(d**2)**3")]),
             ("springs[0].potential", "not twice differentiable")),
    "no_minimum": (masses_toml("no_minimum", {"k": 1}, {"p": "1"}, [("wall", "p", "exp(k*d)")]),
                   ("springs[0].potential", "no static equilibrium found")),
    "free_gravity": (masses_toml("free_gravity", {"k": 1, "g": 1}, {"p": "1", "q": "1"}, [("p", "q", "k*d**2/2 + d**4")],
                                 extra='[gravity]\ng = "g"\n'),
                     ("gravity", "no static equilibrium")),
    "chain_negative": (chain_text("chain_negative", {"m": 1, "k": 1}, 10, "k*(i - 3)*d**2/2"),
                       ("chain.potential", "not positive for the spring i = -1")),
    "chain_prestressed_free": (chain_text("chain_prestressed_free", {"m": 1, "k": 1}, 10, "k*(d - 1)**2/2",
                                          left="free", right="free"),
                               ("chain.potential", "V'(0) = -k is not 0")),
    "chain_gravity": (chain_text("chain_gravity", {"m": 1, "k": 1, "g": 1}, 10, "k*d**2/2 + d**4",
                                 extra='[gravity]\ng = "g"'), ("gravity", "constant load on a chain")),
    # oracle N10: a load that varies with t about a nonzero mean is a constant load plus a zero-mean one
    "chain_force_mean": (chain_text("chain_force_mean", {"m": 1, "k": 1}, 3, "k*d**2/2 + d**4", right="free",
                                    extra='[[forces]]\non = 2\nf = "0.5 + 0.5*sin(2*t)"'),
                         ("forces[0]", "constant load on a chain", "constant part of the force")),
    "chain_force_square": (chain_text("chain_force_square", {"m": 1, "k": 1}, 3, "k*d**2/2 + d**4", right="free",
                                      extra='[[forces]]\non = 1\nf = "sin(t)**2"'),
                           ("forces[0]", "constant load on a chain", "constant part of the force")),
    "chain_ground_mean": (chain_text("chain_ground_mean", {"m": 1, "k": 1}, 3, "k*d**2/2 + d**4", right="free",
                                     extra='[ground]\nacceleration = "1 + cos(t)"'),
                          ("ground.acceleration", "constant load on a chain", "ground acceleration")),
    "param_d": (masses_toml("param_d", {"d": 1}, {"p": "1"}, [("wall", "p", "d*x")]),
                ("parameters.d", "d is the spring's extension")),
    "param_log": (masses_toml("param_log", {"log": 1}, {"p": "1"}, [("wall", "p", "log(1 + d)")]),
                  ("springs[0].potential", "'log' is a parameter of this scene")),
    "k_and_potential": ('name = "kp"\n[parameters]\nk = 1.0\n[masses]\np = "1"\n[[springs]]\n'
                        'between = ["wall", "p"]\nk = "k"\npotential = "k*d**2/2"\n',
                        ("springs[0].k", "unknown key")),
    "chain_k_and_potential": (chain_text("ckp", {"m": 1, "k": 1}, 4, "k*d**2/2").replace('mass = "m"',
                                                                                        'mass = "m"\nk = "k"'),
                              ("chain.k", "unknown key")),
    "bad_syntax": (masses_toml("bad_syntax", {"k": 1}, {"p": "1"}, [("wall", "p", "k*d**2/2 + __import__(1)")]),
                   ("springs[0].potential",)),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refusals_are_one_line(case, tmp_path, capsys):
    text, parts = REFUSED[case]
    path = tmp_path / f"{case}.toml"
    path.write_text(text)
    for command in (["modes"], ["derive", "--out", tmp_path / "gen"]):
        status, _, err = run_cli([command[0], path, *command[1:]], capsys)
        one_line_error(status, err, str(path), *parts)
    assert not (tmp_path / "gen").exists() or not any((tmp_path / "gen").iterdir())


def test_chain_potential_with_zero_mean_loads_is_linearised_about_zero(capsys, tmp_path):
    """Loads with no constant part (cos(t)*sin(t) = sin(2t)/2, cos(3t + 1)) leave a potential chain's
    equilibrium at x = 0: modes are those of k = V''(0), by hand ω_j² = 4 k sin²(π(2j − 1)/(2(2n + 1)))/m."""
    path = tmp_path / "zm.toml"
    path.write_text(chain_text("zm", {"m": 1, "k": 1}, 3, "k*d**2/2 + d**4", right="free",
                               extra='[[forces]]\non = 2\nf = "cos(t)*sin(t)"\n[ground]\n'
                                     'acceleration = "cos(3*t + 1)"'))
    status, out, err = run_cli(["modes", path, "--json"], capsys)
    assert status == 0, err
    got = [r["omega2_value"] for r in json.loads(out)["modes"]]
    ref = [4 * mpmath.sin(mpmath.pi * (2 * j - 1) / 14) ** 2 for j in (1, 2, 3)]
    assert np.allclose(got, [float(v) for v in ref], rtol=4e-16, atol=0)


# -- exact symbolic results on small cases ----------------------------------------------------------
def test_toda_masses_terms_and_hessian_exact(scene_from_text):
    from springchain.derive.model import Effect, Model

    text = masses_toml("toda3", {"m": 1, "a": 1, "b": 2}, {"p": "m", "q": "m", "r": "m"},
                       [("wall", "p", "a/b*exp(-b*d) + a*d"), ("p", "q", "a/b*exp(-b*d) + a*d"),
                        ("q", "r", "a/b*exp(-b*d) + a*d"), ("r", "wall", "a/b*exp(-b*d) + a*d")])
    model = Model(scene_from_text(text, "toda3.toml"))
    a, b = model.params["a"], model.params["b"]
    x = model.x
    # V written independently: d = x_b - x_a with walls at 0
    ext = [x[0], x[1] - x[0], x[2] - x[1], -x[2]]
    V = sum(a / b * sp.exp(-b * d) + a * d for d in ext)
    assert sp.simplify(model.V - V) == 0
    forces = model.force_expressions(Effect.POTENTIAL)
    for i in range(3):
        assert sp.simplify(forces[i] + sp.diff(V, x[i])) == 0
    H = sp.hessian(V, x).subs({xi: 0 for xi in x})
    assert sp.simplify(model.K - H) == sp.zeros(3, 3)
    assert model.equilibrium.at_rest and model.equilibrium.closed_form
    assert not model.linear


def test_quadratic_potential_is_a_linear_spring(scene_from_text):
    from springchain._modules import derive

    springs = "\n".join(['[[springs]]\nbetween = ["wall", "p"]\npotential = "k*d**2/2"',
                         '[[springs]]\nbetween = ["p", "q"]\npotential = "3*k*d**2/2"'])
    text = f'name = "quad"\n[parameters]\nm = 1.0\nk = 2.0\n[masses]\np = "m"\nq = "2*m"\n{springs}\n'
    d = derive(scene_from_text(text, "quad.toml"))
    k, m = d.model.params["k"], d.model.params["m"]
    assert d.model.linear and d.model.K == sp.Matrix([[4 * k, -3 * k], [-3 * k, 3 * k]])
    w = sp.Symbol("w")
    expected = sorted(sp.solve((sp.Matrix([[4, -3], [-3, 3]]) - w * sp.diag(1, 2)).det(), w), key=float)
    got = sorted((sp.simplify(mode.omega2 * m / k) for mode in d.modes.modes), key=float)
    assert all(sp.simplify(a - b) == 0 for a, b in zip(got, expected))
    assert "LINEAR = True" in d.source


def test_chain_interior_equation_exact(scene_from_text):
    from springchain.derive.chain import ChainModel

    model = ChainModel(scene_from_text(chain_text("morse", {"m": 1, "D": 2, "w": 1.5}, 8, "D*(1 - exp(-w*d))**2"),
                                       "morse.toml"))
    D, w = model.params["D"], model.params["w"]
    V = lambda d: D * (1 - sp.exp(-w * d)) ** 2  # noqa: E731
    expected = -sp.diff(V(model.x0 - model.xm) + V(model.xp - model.x0), model.x0)
    assert sp.simplify(model.interior_equation() - expected) == 0
    assert sp.simplify(model.k - 2 * D * w**2) == 0 and model.tension == 0 and not model.linear


# -- the static equilibrium ---------------------------------------------------------------------------------
HANG = masses_toml("hang", {"m": 1.0, "k": 1.0, "beta": 0.5, "g": 0.3, "D": 3.0, "w": 0.7},
                   {"p": "m", "q": "2*m", "r": "m"},
                   [("wall", "p", "k*d**2/2 + beta*d**4/4"), ("p", "q", "D*(1 - exp(-w*d))**2"),
                    ("q", "r", "k*d**2/2 + beta*d**4/4"), ("r", "wall", "k*d**2/2")], extra='[gravity]\ng = "g"\n')


def _reference_gradient(text, x, dps=60):
    """∂U/∂x of the scene written in `text`, by SymPy on parse_expr'd potentials, in mpmath."""
    import tomllib

    data = tomllib.loads(text)
    params = {k: sp.Rational(repr(float(v))) for k, v in data["parameters"].items()}
    names = list(data["masses"])
    X = sp.symbols(f"X0:{len(names)}")
    local = {k: sp.Symbol(k) for k in params}
    U = 0
    for s in data["springs"]:
        a, b = s["between"]
        xa = 0 if a == "wall" else X[names.index(a)]
        xb = 0 if b == "wall" else X[names.index(b)]
        V = parse_expr(s["potential"], local_dict={**local, "d": sp.Symbol("d")})
        U += V.subs(sp.Symbol("d"), xb - xa)
    g = parse_expr(data["gravity"]["g"], local_dict=local) if "gravity" in data else 0
    for j, mname in enumerate(names):
        U -= parse_expr(data["masses"][mname], local_dict=local) * g * X[j]
    U = U.subs({local[k]: v for k, v in params.items()})
    grad = [sp.diff(U, xi) for xi in X]
    hess = sp.hessian(U, X)
    with mpmath.workdps(dps):
        xs = {xi: sp.Float(repr(float(v)), dps) for xi, v in zip(X, x)}
        G = [float(sp.N(gi.subs(xs), dps)) for gi in grad]
        H = np.array([[float(sp.N(hij.subs(xs), dps)) for hij in row] for row in hess.tolist()])
    return np.array(G), H


def test_numeric_equilibrium_against_independent_gradient(scene_from_text, import_source):
    from springchain._modules import derive

    d = derive(scene_from_text(HANG, "hang.toml"))
    eq = d.model.equilibrium
    assert not eq.closed_form
    mod = import_source(d.source, "hang")
    x_eq = mod.equilibrium(**mod.DEFAULTS)
    G, H = _reference_gradient(HANG, x_eq)
    # the correctly rounded root: one Newton correction (60 digits) moves it by at most an ulp or two
    assert np.max(np.abs(np.linalg.solve(H, G))) <= 4 * np.finfo(float).eps * np.max(np.abs(x_eq))
    # K printed and generated = the Hessian at x_eq
    K_gen = np.asarray(mod.stiffness_matrix(**mod.DEFAULTS), dtype=float)
    assert np.allclose(K_gen, H, rtol=1e-13, atol=0)
    data = json.loads(json.dumps(__import__("springchain").modes(d.scene).to_json()))
    assert data["equilibrium"]["closed_form"] is False
    assert np.allclose(data["equilibrium"]["x_value"], x_eq, rtol=0, atol=0)
    with pytest.raises(ValueError, match="DEFAULTS only"):
        mod.equilibrium(**{**mod.DEFAULTS, "g": 1.0})


def test_modes_json_of_a_potential_chain(capsys):
    status, out, _ = run_cli(["modes", "toda", "--json"], capsys)
    assert status == 0
    data = json.loads(out)
    assert data["equilibrium"]["x"] == "0" and data["equilibrium"]["stiffness"] == "a*b"
    assert data["family"]["omega2"] == "4*a*b*sin(pi*j/(2*n))**2/m"
    assert any("linearisation" in note for note in data["notes"])
    status, out, _ = run_cli(["modes", "toda"], capsys)
    assert "Static equilibrium: x = 0" in out and "stiffness about it k(i) = V''(0) = a*b" in out


DAMPED_HANG = """name = "eqjson"

[parameters]
m = 1.0
k = 2.0
beta = 0.5
g = -1.0
c = 0.1

[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
potential = "k*d**2/2 + beta*d**4/4"
[[dampers]]
between = ["p", "wall"]
c = "c"
[gravity]
g = "g"
"""


def test_modes_json_of_a_damped_potential_scene_keeps_its_equilibrium(scene_from_text):
    """Oracle N1: the damping fields were put in place of the equilibrium (they must sit beside it)."""
    import springchain

    data = json.loads(json.dumps(springchain.modes(scene_from_text(DAMPED_HANG, "eqjson.toml")).to_json()))
    # independent reference: k d + beta d^3 = m g (d = x, one spring to the wall), mpmath at 50 digits
    with mpmath.workdps(50):
        d = mpmath.findroot(lambda d: 2 * d + mpmath.mpf("0.5") * d**3 + 1, -0.5)
        k_eq = 2 + 3 * mpmath.mpf("0.5") * d**2
        zeta = mpmath.mpf("0.1") / (2 * mpmath.sqrt(k_eq))
    assert np.allclose(data["equilibrium"]["x_value"], [float(d)], rtol=4e-16, atol=0)
    assert data["damping"]["proportional"] is True
    assert data["modes"][0]["omega2_value"] == pytest.approx(float(k_eq), rel=4e-16)
    assert data["modes"][0]["damping_ratio"] == pytest.approx(float(zeta), rel=4e-16)


# -- generated forces = the SymPy derivative, on potentials this file did not write -----------------------
def _block(draw):
    s = draw(st.sampled_from(["1/2", "3/4", "1", "3/2", "2"]))
    c = draw(st.sampled_from(["1/3", "1/2", "1", "2", "5"]))
    forms = [
        f"{c}*d**2/2", f"{c}*d**4/4", f"{c}*d**3/3", f"{c}*(exp({s}*d) - {s}*d)", f"{c}*(exp(-{s}*d) + {s}*d)",
        f"{c}*cosh({s}*d)", f"{c}*({s}*d - log(1 + {s}*d/4)*4)", f"{c}*(1 - exp(-{s}*d))**2",
        f"{c}*((1/(1 + {s}*d/4))**12 - 2*(1/(1 + {s}*d/4))**6)", f"{c}*sqrt(1 + ({s}*d)**2)",
        f"{c}*log(cosh({s}*d))", f"{c}*d*tanh({s}*d)", f"{c}*(cosh(sinh({s}*d)) - 1)",
        f"{c}*exp({s}*d**2)", f"{c}*(1 - cos({s}*d))", f"{c}*(sinh({s}*d) - {s}*d)**2 + {c}*d**2",
    ]
    return draw(st.sampled_from(forms))


@st.composite
def potentials(draw):
    """d²/2 (a linear part, so that V''(0) > 0) plus one to three drawn blocks, each with V'(0) = 0."""
    return " + ".join(["d**2/2"] + [_block(draw) for _ in range(draw(st.integers(1, 3)))])


@settings(max_examples=12)
@given(pot=potentials(), seed=st.integers(0, 2**32 - 1))
def test_generated_force_equals_sympy_derivative(pot, seed, scene_from_text, import_source):
    """spring_force of the generated module vs SymPy's V'(d) in 60-digit mpmath at random d: relative
    error ≤ 1e-13 wherever V' is well conditioned in d (|d V''/V'| ≤ 100: every point near d = 0)."""
    from springchain._modules import derive

    text = chain_text("drawn", {"m": 1.0}, 4, pot, left="wall", right="wall")
    d = derive(scene_from_text(text, "drawn.toml"))
    mod = import_source(d.source, "drawn")
    dd = sp.Symbol("d")
    V = parse_expr(pot, local_dict={"d": dd})
    F, S = sp.diff(V, dd), sp.diff(V, dd, 2)
    f_mp = sp.lambdify(dd, F, "mpmath")
    s_mp = sp.lambdify(dd, S, "mpmath")
    e_mp = sp.lambdify(dd, V - V.subs(dd, 0), "mpmath")
    rng = np.random.default_rng(seed)
    r = 0.5  # the run's range of d: |s d/4| ≤ 1/4 keeps every log and pole away
    pts = np.concatenate([rng.uniform(-r, r, 40), rng.choice([-1, 1], 40) * 10 ** rng.uniform(-12, np.log10(r), 40)])
    got = np.asarray(mod.spring_force(pts, **mod.DEFAULTS), dtype=float)
    got_e = np.asarray(mod.spring_energy(pts, **mod.DEFAULTS), dtype=float)
    worst = worst_e = 0.0
    with mpmath.workdps(60):
        for x, g, ge in zip(pts, got, got_e):
            f = f_mp(mpmath.mpf(float(x)))
            if f == 0 or abs(x * s_mp(mpmath.mpf(float(x))) / f) > 100:
                continue
            worst = max(worst, float(abs((g - f) / f)))
            e = e_mp(mpmath.mpf(float(x)))
            if e != 0 and abs(x * f / e) <= 100:
                worst_e = max(worst_e, float(abs((ge - e) / e)))
    assert worst <= 1e-13, (pot, worst)
    assert worst_e <= 1e-12, (pot, worst_e)


def test_named_potentials_force_and_energy_accuracy(scene_from_text, import_source):
    """FPUT-α/β, Toda, Morse and a Lennard-Jones pair about its minimum, in [masses] form
    (spring_tensions) and [chain] form (spring_force): ≤ 1e-13 relative from 1e-12 to 0.5."""
    from springchain._modules import derive

    named = {"fput_a": "k*d**2/2 + alpha*d**3/3", "fput_b": "k*d**2/2 + beta*d**4/4",
             "toda": "a/b*exp(-b*d) + a*d", "morse": "D*(1 - exp(-w*d))**2",
             "lj": "eps*((r0/(r0 + d))**12 - 2*(r0/(r0 + d))**6)"}
    params = {"m": 1.0, "k": 1.0, "alpha": 0.25, "beta": 1.0, "a": 1.0, "b": 1.7, "D": 2.0, "w": 1.3,
              "eps": 0.5, "r0": 1.1}
    pts = np.concatenate([np.logspace(-12, np.log10(0.5), 60), -np.logspace(-12, np.log10(0.5), 60)])
    for name, pot in named.items():
        text = masses_toml(name, params, {"p": "m"}, [("wall", "p", pot)])
        mod = import_source(derive(scene_from_text(text, f"{name}.toml")).source, name)
        got = mod.spring_tensions(pts[None, :], **mod.DEFAULTS)[0]
        dd = sp.Symbol("d")
        V = parse_expr(pot, local_dict={"d": dd, **{p: sp.Rational(repr(v)) for p, v in params.items()}})
        f_mp = sp.lambdify(dd, sp.diff(V, dd), "mpmath")
        with mpmath.workdps(60):
            err = max(float(abs((g - f_mp(mpmath.mpf(float(x)))) / f_mp(mpmath.mpf(float(x)))))
                      for x, g in zip(pts, got))
        assert err <= 1e-13, (name, err)
