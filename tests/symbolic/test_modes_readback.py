"""Issue 9, item 5: ``omega2`` and ``shape`` strings of ``modes --json`` read back with the scene's symbols.

``sympify`` would read parameters named ``E``, ``I``, ``S``, ``Q``, ``N``, ``O``, ``beta``,
``gamma``, ``zeta`` ... as SymPy's constants or functions. ``springchain.parse_expression``
(and ``Modes.parse``) build the scene's own symbols through the whitelist parser; here
the round trip is checked for every such name (quadratic roots with sqrt, Viète cubic
roots with acos/cos, numeric fallbacks) and for hypothesis-drawn identifiers.
"""

from __future__ import annotations

import keyword

import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import springchain
from springchain.derive.errors import SceneError
from springchain.derive.scene import RESERVED, RESERVED_PREFIXES

CLASHES = ["E", "I", "S", "Q", "N", "O", "beta", "gamma", "zeta", "Lambda", "oo", "zoo", "nan", "acos",
           "Float", "Symbol", "Rational", "Integer", "Abs", "re", "im", "lambda_", "sympify", "Pi", "EulerGamma",
           "Catalan", "GoldenRatio", "true", "None_", "evaluate"]


def _scene(tmp_path, names, layout="wall2"):
    """Two masses wall–k–m1–k2–m2 (quadratic roots), or three masses between walls (a cubic)."""
    a, b, c = names
    if layout == "wall2":
        body = (f'[parameters]\n{a} = 1.5\n{b} = 0.25\n{c} = 40.0\n\n[masses]\nx0 = "{a}"\nx1 = "{b}"\n\n'
                f'[[springs]]\nbetween = ["wall", "x0"]\nk = "{c}"\n\n'
                f'[[springs]]\nbetween = ["x0", "x1"]\nk = "3*{c}"\n')
        n = 2
    else:  # three masses between walls: an irreducible cubic in Viète's form
        body = (f'[parameters]\n{a} = 1.5\n{b} = 0.25\n{c} = 40.0\n\n[masses]\nx0 = "{a}"\nx1 = "2*{a}"\n'
                f'x2 = "4*{a}"\n\n'
                + "".join(f'[[springs]]\nbetween = ["{p}", "{q}"]\nk = "{c}"\n\n'
                          for p, q in (("wall", "x0"), ("x0", "x1"), ("x1", "x2"), ("x2", "wall"))))
        n = 3
    text = (f'name = "rb"\ndescription = "read back"\n\n{body}\n[initial]\nx = [{", ".join(["0.1"] * n)}]\n'
            f'v = [{", ".join(["0.0"] * n)}]\n\n[simulation]\ndt = 0.01\nsteps = 10\n')
    path = tmp_path / f"rb_{'_'.join(names)}_{layout}.toml"
    path.write_text(text, encoding="utf-8")
    return springchain.load(path)


def _round_trip(scene):
    """Every printed omega2 and shape string parses back to the derivation's expression."""
    m = springchain.modes(scene)
    data = m.to_json()
    exprs = {mode.omega2 for mode in m.modes.modes}
    shapes = {tuple(s) for mode in m.modes.modes for s in mode.shapes}
    assert data["modes"]
    for rec in data["modes"]:
        w2 = m.parse(rec["omega2"])
        assert w2 == springchain.parse_expression(rec["omega2"], scene)
        if all(mode.exact for mode in m.modes.modes):
            assert w2 in exprs, (rec["omega2"], w2, exprs)
            assert tuple(m.parse(c) for c in rec["shape"]) in shapes
        else:  # numeric modes: the printed 17 digits, exactly
            assert w2 == sp.Rational(rec["omega2"])
    return m


@pytest.mark.parametrize("names", [CLASHES[i:i + 3] for i in range(0, len(CLASHES), 3)],
                         ids=lambda n: "-".join(n))
def test_clashing_names_read_back(tmp_path, names):
    m = _round_trip(_scene(tmp_path, names))
    syms = {s.name for e in m.omega2 for s in e.free_symbols}
    assert syms <= set(names) and names[2] in syms  # the stiffness is in every non-rigid ω²


@pytest.mark.parametrize("names", [["E", "I", "S"], ["beta", "gamma", "zeta"], ["Q", "acos", "N"]],
                         ids=lambda n: "-".join(n))
def test_cubic_roots_read_back(tmp_path, names):
    """Viète's form (acos, cos, pi) with clashing names."""
    m = _round_trip(_scene(tmp_path, names, "cubic"))
    assert any(e.has(sp.acos) for e in m.omega2)


def test_clashing_names_are_the_scenes_symbols(tmp_path):
    """I stays the parameter I (positive, as in the derivation), never the imaginary unit."""
    m = springchain.modes(_scene(tmp_path, ["I", "S", "E"]))
    e = m.parse(m.to_json()["modes"][0]["omega2"])
    assert e == m.omega2[0] and not e.has(sp.I) and all(s.is_positive for s in e.free_symbols)
    assert {s.name for s in e.free_symbols} == {"I", "S", "E"}


def test_read_back_refuses_unknown_names_and_code(tmp_path):
    scene = _scene(tmp_path, ["E", "I", "S"])
    for bad in ["F*2", "__import__('os')", "E.real", "lambda: 1", "E**S"]:
        with pytest.raises(SceneError):
            springchain.parse_expression(bad, scene)


_IDENT = st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,6}", fullmatch=True).filter(
    lambda s: not keyword.iskeyword(s) and s not in RESERVED and not s.startswith(RESERVED_PREFIXES)
    and s not in ("x0", "x1", "x2"))


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(names=st.lists(_IDENT, min_size=3, max_size=3, unique=True))
def test_any_identifier_reads_back(tmp_path, names):
    _round_trip(_scene(tmp_path, names))
