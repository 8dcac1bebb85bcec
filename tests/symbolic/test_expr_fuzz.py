"""Fuzzing the safe expression parser (and the scene loader) with hypothesis.

* Random *valid* expression trees are drawn by a strategy that renders them as
  text and, independently of :mod:`derive.expr`, knows their value (plain
  ``math`` floats), their exact value (``mpmath`` at 60 digits) and their SymPy
  form. The parser must accept the text, ``evaluate`` must agree with the
  float reference, the rounding-error bound of ``evaluate_error`` must hold
  against the exact value, and ``to_sympy`` must equal the SymPy form.
* Random text (printable ASCII, any Unicode, Python-like token soup) must
  either parse or raise :class:`SceneError`, nothing else; the work done is
  bounded (``ast.parse`` never sees more than MAX_LENGTH characters or deeper
  nesting than MAX_DEPTH), and a hang guard stops a runaway case.
* Random mutations of a valid scene file either load or raise SceneError.
"""

from __future__ import annotations

import ast
import contextlib
import math
import signal
import string
import warnings
from unittest import mock
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

import springchain.derive.expr as expr_mod
from springchain.derive.errors import SceneError
from springchain.derive.expr import MAX_DEPTH, MAX_LENGTH, MAX_TOTAL_EXPONENT, parse_expression
from springchain.derive.scene import load_scene

EXAMPLES = max(200, settings.default.max_examples)
NAMES = ("a", "b", "c")
ALLOWED = frozenset(NAMES)
SYMBOLS = {n: sp.Symbol(n, real=True) for n in NAMES}


@contextlib.contextmanager
def hang_guard(seconds: int = 20):
    """Fail (rather than hang the suite) if the block runs away. Not a timing assertion."""
    if not hasattr(signal, "SIGALRM"):
        yield
        return

    def boom(*_):
        raise AssertionError(f"no answer within {seconds} s: unbounded work")

    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


# -- a strategy of valid expression trees ------------------------------------------------------
@dataclass(frozen=True)
class Tree:
    """A valid expression: its text and three independent meanings."""

    text: str
    kind: str
    parts: tuple

    def value(self, env: dict[str, float]) -> float:
        """Floating-point value with ``math`` (nan where Python raises)."""
        try:
            return self._value(env)
        except (ValueError, ZeroDivisionError, OverflowError):
            return math.nan

    def _value(self, env):
        k, p = self.kind, self.parts
        if k == "num":
            return float(p[0])
        if k == "name":
            return env[p[0]]
        if k == "pi":
            return math.pi
        if k == "neg":
            return -p[0]._value(env)
        if k == "bin":
            a, b = p[1]._value(env), p[2]._value(env)
            return {"+": lambda: a + b, "-": lambda: a - b, "*": lambda: a * b,
                    "/": lambda: _ieee_div(a, b), "%": lambda: a % b if b != 0 else math.nan}[p[0]]()
        if k == "pow":
            return _ieee_pow(p[0]._value(env), float(p[1]))
        arg = p[1]._value(env)
        if p[0] == "exp":
            try:
                return math.exp(arg)
            except OverflowError:
                return math.inf
        try:
            return getattr(math, p[0])(arg)
        except ValueError:  # sqrt(-1), sin(inf)
            return math.nan

    def exact(self, env: dict[str, float]):
        """Value at 60 digits with mpmath (None where undefined or complex)."""
        with mpmath.workdps(60):
            try:
                v = self._exact(env)
            except (ValueError, ZeroDivisionError, OverflowError):
                return None
            return v if isinstance(v, mpmath.mpf) and mpmath.isfinite(v) else None

    def _exact(self, env):
        k, p = self.kind, self.parts
        if k == "num":
            return mpmath.mpf(p[0].numerator) / p[0].denominator
        if k == "name":
            return mpmath.mpf(env[p[0]])
        if k == "pi":
            return +mpmath.pi
        if k == "neg":
            return -p[0]._exact(env)
        if k == "bin":
            a, b = p[1]._exact(env), p[2]._exact(env)
            if p[0] == "/" and b == 0:
                raise ZeroDivisionError
            if p[0] == "%":
                if b == 0:
                    raise ZeroDivisionError
                return a - b * mpmath.floor(a / b)
            return {"+": a + b, "-": a - b, "*": a * b, "/": a / b if b else None}[p[0]]
        if k == "pow":
            base, e = p[0]._exact(env), p[1]
            if base == 0 and e < 0:
                raise ZeroDivisionError
            if base < 0 and e.denominator != 1:
                raise ValueError
            return mpmath.power(base, mpmath.mpf(e.numerator) / e.denominator)
        arg = p[1]._exact(env)
        if p[0] == "sqrt" and arg < 0:
            raise ValueError
        if p[0] in ("sin", "cos") and abs(arg) > 1e6:  # float64 has no digits left for the phase
            raise ValueError
        if p[0] == "exp" and abs(arg) > 1e4:  # beyond float64 either way; mpmath would take minutes
            raise OverflowError
        return getattr(mpmath, p[0])(arg)

    def sympy(self):
        """The SymPy expression, built here from the tree (not by derive.expr)."""
        k, p = self.kind, self.parts
        if k == "num":
            return sp.Rational(p[0].numerator, p[0].denominator)
        if k == "name":
            return SYMBOLS[p[0]]
        if k == "pi":
            return sp.pi
        if k == "neg":
            return -p[0].sympy()
        if k == "bin":
            a, b = p[1].sympy(), p[2].sympy()
            return {"+": lambda: a + b, "-": lambda: a - b, "*": lambda: a * b, "/": lambda: a / b,
                    "%": lambda: sp.Mod(a, b)}[p[0]]()
        if k == "pow":
            return p[0].sympy() ** sp.Rational(p[1].numerator, p[1].denominator)
        return getattr(sp, p[0])(p[1].sympy())


def _ieee_div(a: float, b: float) -> float:
    """a / b with IEEE 754 results for b = 0 (Python raises)."""
    if b != 0 or math.isnan(b):
        return a / b
    if a == 0 or math.isnan(a):
        return math.nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)


def _ieee_pow(a: float, p: float) -> float:
    """a ** p with IEEE 754 results where math.pow raises."""
    odd = p == int(p) and int(p) % 2 == 1
    try:
        return math.pow(a, p)
    except ValueError:  # 0 ** negative, or negative ** fraction
        return (math.copysign(math.inf, a) if odd else math.inf) if a == 0 else math.nan
    except OverflowError:
        return -math.inf if (a < 0 and odd) else math.inf


def _num_text(x) -> tuple[str, Fraction]:
    if isinstance(x, int):
        return str(x), Fraction(x)
    text = repr(x)
    return text, Fraction(text)


numbers = st.one_of(st.integers(0, 1000), st.floats(0, 1e6, allow_nan=False, allow_infinity=False),
                    st.sampled_from([0.5, 0.1, 1e-3, 2.5e-7, 3e8]))
EXPONENTS = [Fraction(v) for v in (-3, -2, -1, 0, 1, 2, 3, 4)] + [Fraction(1, 2), Fraction(-1, 2), Fraction(3, 2),
                                                                    Fraction(1, 3)]


@st.composite
def trees(draw, depth: int = 5, power: float = 1.0) -> Tree:
    """A valid expression of at most ``depth`` levels whose powers of powers stay within bounds."""
    choices = ["num", "name", "name", "pi"] + (["neg", "bin", "bin", "bin", "pow", "call"] if depth > 0 else [])
    kind = draw(st.sampled_from(choices))
    if kind == "num":
        text, value = _num_text(draw(numbers))
        return Tree(text, "num", (value,))
    if kind == "name":
        name = draw(st.sampled_from(NAMES))
        return Tree(name, "name", (name,))
    if kind == "pi":
        return Tree("pi", "pi", ())
    if kind == "neg":
        t = draw(trees(depth - 1, power))
        return Tree(f"(-{t.text})", "neg", (t,))
    if kind == "bin":
        op = draw(st.sampled_from("+-*/%"))
        a = draw(trees(depth - 1, power))
        if op == "%":  # the divisor must be a nonzero constant
            text, value = _num_text(draw(numbers.filter(lambda x: x != 0)))
            b = Tree(text, "num", (value,))
        else:
            b = draw(trees(depth - 1, power))
        spaced = draw(st.booleans())
        return Tree(f"({a.text} {op} {b.text})" if spaced else f"({a.text}{op}{b.text})", "bin", (op, a, b))
    if kind == "pow":
        e = draw(st.sampled_from([p for p in EXPONENTS if power * max(1, abs(p)) <= MAX_TOTAL_EXPONENT]))
        base = draw(trees(depth - 1, power * max(1.0, float(abs(e)))))
        etext = str(e.numerator) if e.denominator == 1 else f"{e.numerator}/{e.denominator}"
        return Tree(f"({base.text})**({etext})", "pow", (base, e))
    func = draw(st.sampled_from(("sqrt", "sin", "cos", "exp")))
    arg = draw(trees(depth - 1, power))
    return Tree(f"{func}({arg.text})", "call", (func, arg))


envs = st.fixed_dictionaries({n: st.floats(-50, 50, allow_nan=False, allow_infinity=False) for n in NAMES})


def _both_nonfinite(a, b) -> bool:
    return not math.isfinite(a) and not math.isfinite(b)


@settings(max_examples=EXAMPLES)
@given(trees(), envs)
@example(Tree("sin(pi)", "call", ("sin", Tree("pi", "pi", ()))), {"a": 0.0, "b": 0.0, "c": 0.0})
def test_valid_trees_parse_and_evaluate_like_the_reference(tree, env):
    assert len(tree.text) <= MAX_LENGTH
    e = parse_expression(tree.text, ALLOWED)
    got = float(np.asarray(e.evaluate(env), dtype=float))
    want = tree.value(env)
    value, bound = e.evaluate_error(env)
    value = float(value)
    assert value == got or _both_nonfinite(value, got)  # same value with or without the bound
    if _both_nonfinite(got, want):
        return
    # libm (math) and NumPy may differ by an ulp per function call; the error bound covers that
    tol = 1e-9 * max(abs(got), abs(want)) + 1e-300 + 4 * float(bound)
    assert math.isfinite(got) and math.isfinite(want) and abs(got - want) <= tol, (tree.text, got, want, bound)
    assert e.symbols() <= ALLOWED
    assert e.symbols() == frozenset(n for n in NAMES if n in _names(tree))


def _names(tree: Tree) -> set[str]:
    if tree.kind == "name":
        return {tree.parts[0]}
    return set().union(*(_names(p) for p in tree.parts if isinstance(p, Tree)))


@settings(max_examples=EXAMPLES)
@given(trees(), envs)
def test_error_bound_holds_against_exact_arithmetic(tree, env):
    """evaluate_error's bound is what makes 'sin(pi) is not a positive mass' decidable: it must hold."""
    e = parse_expression(tree.text, ALLOWED)
    value, bound = (float(np.asarray(v)) for v in e.evaluate_error(env))
    assume(math.isfinite(value) and math.isfinite(bound))
    # first-order analysis: meaningful where the bound is small against the value or absolute
    assume(bound <= 1e-3 * max(abs(value), 1.0))
    exact = tree.exact(env)  # after the cheap filters: exact arithmetic on exp(1e300) never ends
    assume(exact is not None)
    with mpmath.workdps(60):
        err = abs(mpmath.mpf(value) - exact)
    assert err <= 2 * bound + 1e-300, (tree.text, value, float(exact), bound)


@settings(max_examples=max(60, settings.default.max_examples))
@given(trees(depth=4), envs)
@example(Tree("((pi%1.689051076064978e-212)%1)", "bin", ("%", Tree("(pi%1.689051076064978e-212)", "bin", (
    "%", Tree("pi", "pi", ()), Tree("1.689051076064978e-212", "num", (Fraction("1.689051076064978e-212"),)))),
    Tree("1", "num", (Fraction(1),)))), {"a": 1.0, "b": 1.0, "c": 1.0})
def test_to_sympy_equals_an_independent_sympy_build(tree, env):
    """Every expression the scene check accepts (finite value and error bound at the parameter
    values) builds in SymPy, quickly, as the same expression a SymPy user would write.

    The bound matters: SymPy raises 'not computing with precision' for Mod(pi % 1e-212, 1), and
    would spend minutes on Mod(exp(745612.5), 372806.25) (inf in floating point)."""
    e = parse_expression(tree.text, ALLOWED)
    value, bound = (np.asarray(v, dtype=float) for v in e.evaluate_error(env))
    assume(np.isfinite(value) and np.isfinite(bound))
    with hang_guard(30):
        got = e.to_sympy(SYMBOLS)
        want = tree.sympy()
        if got != want:
            _same_numbers(tree, got, want)


def _same_numbers(tree: Tree, got, want) -> None:
    """Not structurally equal: compare in complex floating point at random points."""
    args = [SYMBOLS[n] for n in NAMES]
    fg, fw = (sp.lambdify(args, ex, modules="numpy") for ex in (got, want))
    rng = np.random.default_rng(len(tree.text))
    with np.errstate(all="ignore"):
        for _ in range(3):
            point = rng.uniform(-3, 3, size=len(NAMES)) + 0j
            g, w = complex(fg(*point)), complex(fw(*point))
            if not (np.isfinite(g) and np.isfinite(w)):
                assert not np.isfinite(g) and not np.isfinite(w)
                continue
            assert abs(g - w) <= 1e-9 * (1 + abs(w)), (tree.text, got, want)


# -- random text ---------------------------------------------------------------------------------
TOKENS = ["a", "b", "c", "t", "pi", "sqrt", "sin", "exp", "cos", "abs", "__import__", "os", "eval",
          "lambda", "x", ":", "if", "else", "for", "in", "not", "and", "or", "is", "None", "True",
          "(", ")", "[", "]", "{", "}", ",", ".", "'", '"', "f'", "{a}", "+", "-", "*", "/", "**",
          "//", "%", "@", "^", "~", "<", "==", ":=", "=", "*", "0", "1", "2", "9", "1e308", "1e999",
          "0x1F", "1j", "1_000", "...", ";", "\n", "\\", "#", " ", "\x00", "\u0430", "\uff4b", "\u202e"]
token_soup = st.lists(st.sampled_from(TOKENS), max_size=80).map("".join)
texts = st.one_of(st.text(alphabet=string.printable, max_size=600), st.text(max_size=200), token_soup,
                  trees().map(lambda t: t.text))


@settings(max_examples=EXAMPLES)
@given(texts)
@example("9**9**9")
@example("(" * 1000 + ")" * 1000)
@example("-" * 499 + "1")
@example("not " * 120 + "1")
@example("((((9**16)**16)**16)**16)")
@example("(1,)")
@example("...")
@example("[]")
@example("{}")
@example("a" * 501)
def test_random_text_parses_or_raises_scene_error(text):
    seen: list[str] = []
    real_parse = ast.parse

    def counting_parse(source, *args, **kwargs):
        seen.append(source)
        return real_parse(source, *args, **kwargs)

    with hang_guard(), mock.patch.object(expr_mod.ast, "parse", counting_parse):
        try:
            e = parse_expression(text, ALLOWED | {"t"}, file="f.toml", key="k")
        except SceneError as err:
            msg = str(err)
            assert msg.startswith("f.toml: k: ") and "\n" not in msg and "accepted: " in msg
        else:
            assert isinstance(e, expr_mod.Expr)
            assert e.symbols() <= ALLOWED | {"t"}
    for source in seen:  # the parser only ever sees small, shallow input
        assert len(source) <= MAX_LENGTH and expr_mod._nesting(source) <= MAX_DEPTH


@pytest.mark.parametrize("text", ["1and a", "1or a", "0x1for", "'\\d'", "1if a else 2", "a is 1"])
def test_parser_emits_no_warnings(text):
    """Python warns (SyntaxWarning, DeprecationWarning) on some odd literals: that would be a second
    line on stderr. The parser must stay silent and give one SceneError."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(SceneError):
            parse_expression(text, ALLOWED)
    assert caught == []


@pytest.mark.parametrize("value", [None, [], {}, [1], {"a": 1}, True, False, float("nan"), float("inf"),
                                   -float("inf"), 10**400, 1e301, object(), b"k", 2.5, 7, -3])
def test_non_string_values(value):
    try:
        e = parse_expression(value, ALLOWED)
    except SceneError as err:
        assert "\n" not in str(err)
    else:
        assert isinstance(value, (int, float)) and not isinstance(value, bool)
        assert float(e.evaluate({})) == pytest.approx(float(value))


@pytest.mark.parametrize("exc", [RecursionError, MemoryError, ValueError, SyntaxError, OverflowError])
def test_parser_crash_becomes_scene_error(exc, monkeypatch):
    def crash(*args, **kwargs):
        raise exc("boom")

    monkeypatch.setattr(expr_mod.ast, "parse", crash)
    with pytest.raises(SceneError):
        parse_expression("a + 1", ALLOWED)


@pytest.mark.parametrize("text", ["(1,)", "...", "[]", "{}", "()", "(a, b)", "{a}", "a[0]", "a.real",
                                  "__import__('os')", "(lambda: 1)()", "'a'", "b'a'", "f'{a}'",
                                  "[x for x in ()]", "(a := 1)", "sqrt(*a)", "sqrt(x=a)", "a and b",
                                  "a < b", "a if b else c", "~a", "not a", "a // b", "a @ b", "a ^ b",
                                  "a | b", "a & b", "a << 2", "1j", "await a", "sqrt", "sqrt(a, b)",
                                  "sqrt()", "abs(a)", "pi(1)", "a(1)", "(a)(1)", "a**b", "a**(b)",
                                  "a**17", "a**(1/17)", "a % b", "a % 0", "a % (1 - 1)", "a**(2**5)", "9**9**9", "1e400", "1" + "0" * 400,
                                  "\uff41", "\u0430", "a\x00", "", "   ", "#", "a # comment\nb",
                                  "a;b", "import os", "a\nb"])
def test_forms_that_must_be_refused(text):
    with pytest.raises(SceneError):
        parse_expression(text, ALLOWED)


@pytest.mark.parametrize("text, env, value", [
    ("a*(1 + 2)", {"a": 2.0}, 6.0),
    ("sqrt(a)**3", {"a": 4.0}, 8.0),
    ("a**-1", {"a": 4.0}, 0.25),
    ("a**(1/2)", {"a": 9.0}, 3.0),
    ("-a % 3", {"a": 1.0}, 2.0),
    ("a % (1/2)", {"a": 1.25}, 0.25),
    ("exp(0) + cos(pi) + sin(0)", {}, 0.0),
    ("  a  # trailing comment", {"a": 1.5}, 1.5),
    ("0x10 + 1_000", {}, 1016.0),
])
def test_forms_that_are_accepted(text, env, value):
    assert float(parse_expression(text, ALLOWED).evaluate(env)) == pytest.approx(value)


# -- random scene files ----------------------------------------------------------------------------
SCENE = """name = "s"
description = "fuzz"
[parameters]
m = 1.0
k = 2.0
[masses]
m1 = "m"
m2 = "2*m"
[[springs]]
between = ["m1", "m2"]
k = "k"
[[springs]]
between = ["wall", "m1"]
k = "k/2"
[[dampers]]
between = ["m2", "wall"]
c = 0.1
[[forces]]
on = "m2"
f = "cos(t)"
[initial]
x = [0.1, 0.0]
v = [0.0, 0.0]
[simulation]
dt = 0.1
steps = 100
"""


@st.composite
def mutated_scenes(draw) -> str:
    text = SCENE
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(text)))
        j = draw(st.integers(i, min(len(text), i + 20)))
        insert = draw(st.one_of(st.text(max_size=12), st.sampled_from(
            ["nan", "inf", "-1", "0", "true", '"wall"', "[", "]", "{", "}", "=", "\n[masses]\n", "1e400",
             '"__import__(\'os\')"', "\"m1\"", "[[springs]]\n", '"\u0430"', "9" * 30, "\\u0000"])))
        text = text[:i] + insert + text[j:]
    return text


@settings(max_examples=EXAMPLES)
@given(st.one_of(mutated_scenes(), st.text(max_size=300)))
def test_random_scene_text_loads_or_raises_scene_error(text):
    with hang_guard():
        try:
            scene = load_scene("fuzz.toml", text=text)
        except SceneError as err:
            msg = str(err)
            assert msg.startswith("fuzz.toml") and "\n" not in msg
        else:
            assert scene.n >= 1 and np.all(np.isfinite(scene.x0)) and scene.dt > 0
