"""derive.mp_eval: SymPy expressions evaluated in mpmath by walking the tree, against lambdify."""

from __future__ import annotations

import mpmath
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from springchain.derive.mp_eval import mp_function

a, b, c = sp.symbols("a b c", positive=True)

#: Closed forms of the kinds derive prints (a quadratic pair, Viète's cubic roots) and every node type.
CASES = [
    (a + b) / 2 - sp.sqrt(a**2 + b**2) / 2,
    (35 * a + 4 * c) / (18 * b) - sp.sqrt(901 * a**2 - 128 * a * c + 16 * c**2)
    * sp.cos(sp.acos(sp.Rational(1, 7) * a / (a + b + c)) / 3 + sp.pi / 3) / (9 * b),
    sp.exp(-a) * sp.sin(b) + sp.log(c) * sp.tan(a / (1 + b)) - sp.atan(b) + sp.asin(a / (a + b)),
    sp.cosh(a / 9) - sp.sinh(b / 7) * sp.tanh(c) + sp.atan2(a, -b) + sp.E * sp.pi,
    a ** sp.Rational(1, 3) + b ** sp.Rational(-5, 2) + c**-3 + 1 / sp.sqrt(a + b) + sp.Float(0.1) * a,
    sp.Abs(a - 2 * b) + sp.re(sp.sqrt(a - 3 * b)) + sp.im(sp.sqrt(a - 3 * b)) + sp.conjugate(a + sp.I * b),
    sp.Integer(3),
    sp.Rational(-2, 3),
]


def _values(seed: int):
    return [mpmath.mpf(v) for v in (0.37 + seed, 1.9 + 0.5 * seed, 2.5e-3 * (seed + 1))]


@pytest.mark.parametrize("expr", CASES, ids=range(len(CASES)))
@pytest.mark.parametrize("dps", [30, 60])
def test_equals_lambdify(expr, dps):
    syms = (a, b, c)
    new, old = mp_function(expr, syms), sp.lambdify(syms, expr, modules="mpmath")
    assert getattr(new, "__name__", "") != "_lambdifygenerated"  # the walker, not the fallback
    with mpmath.workdps(dps):
        for seed in range(3):
            got, want = new(*_values(seed)), old(*_values(seed))
            assert abs(got - want) <= mpmath.mpf(10) ** (6 - dps) * max(abs(want), 1), (got, want)


def test_result_follows_the_working_precision():
    f = mp_function(sp.sqrt(a) + sp.pi + sp.Rational(1, 3), (a,))
    with mpmath.workdps(100):
        hi = f(mpmath.mpf(2))
        assert abs(hi - (mpmath.sqrt(2) + mpmath.pi + mpmath.mpf(1) / 3)) < mpmath.mpf(10) ** -98
    with mpmath.workdps(20):
        lo = f(mpmath.mpf(2))
    assert 1e-22 < abs(float(hi - lo)) < 1e-17  # the constants were rounded at 20 digits there


def test_an_integer_power_of_an_integer_stays_exact():
    # SymPy keeps 3**(-k) as a Rational, but an unevaluated power must not become a Python float
    f = mp_function(sp.Pow(sp.Integer(3), -1, evaluate=False) * a, (a,))
    with mpmath.workdps(50):
        assert f(mpmath.mpf(3)) == 1


def test_unknown_nodes_fall_back_to_lambdify():
    f = mp_function(sp.gamma(a) + b, (a, b))
    assert f.__name__ == "_lambdifygenerated"
    with mpmath.workdps(30):
        assert abs(f(mpmath.mpf(5), mpmath.mpf(1)) - 25) < 1e-25


@settings(max_examples=40)
@given(p=st.integers(-50, 50), q=st.integers(1, 60), x=st.floats(1e-6, 1e6), y=st.floats(1e-6, 1e6))
def test_rational_coefficients_and_powers(p, q, x, y):
    expr = sp.Rational(p, q) * a ** 2 - sp.sqrt(a * b + sp.Rational(q, 7)) / (b + 1) ** 3
    new, old = mp_function(expr, (a, b)), sp.lambdify((a, b), expr, modules="mpmath")
    with mpmath.workdps(40):
        got, want = new(mpmath.mpf(x), mpmath.mpf(y)), old(mpmath.mpf(x), mpmath.mpf(y))
        assert abs(got - want) <= mpmath.mpf(10) ** -30 * max(abs(want), abs(sp.Rational(p, q)) * x * x, 1)
