"""Safe expressions from untrusted scene text.

Scene files are untrusted input. An expression such as ``"3*m"`` or
``"F0*cos(Omega*t)"`` is parsed with :func:`ast.parse` and the resulting tree
is walked against a whitelist of node types; anything else (attribute access,
calls to names other than the allowed functions, subscripts, strings,
lambdas, comprehensions, f-strings, non-ASCII names, over-long or
over-deep input) is rejected before anything is evaluated.

The result is a small immutable tree of :class:`Expr` nodes that knows
nothing of SymPy: :meth:`Expr.to_sympy` builds SymPy objects (SymPy is
imported lazily, and only from ``derive/``), and :meth:`Expr.evaluate`
computes a NumPy value from a mapping of names to numbers or arrays. Raw text
is never handed to ``eval``, ``exec``, ``sympify`` or ``parse_expr``.
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Mapping

import numpy as np

from .errors import SceneError

MAX_LENGTH = 500
MAX_NODES = 200
MAX_DEPTH = 24
MAX_EXPONENT = 16
MAX_LITERAL = 1e300

#: Functions a scene expression may call, each with exactly one argument.
FUNCTIONS = ("cos", "exp", "sin", "sqrt")
#: Named constants a scene expression may use.
CONSTANTS = ("pi",)

_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**", ast.Mod: "%"}


@dataclass(frozen=True)
class Expr:
    """Base class of the parsed expression tree."""

    def symbols(self) -> frozenset[str]:
        return frozenset()

    def to_sympy(self, symbols: Mapping[str, object]):  # pragma: no cover - abstract
        raise NotImplementedError

    def evaluate(self, env: Mapping[str, object]):  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass(frozen=True)
class Num(Expr):
    """A finite number literal, kept exact as a fraction of its decimal text."""

    value: Fraction

    def to_sympy(self, symbols):
        import sympy

        return sympy.Rational(self.value.numerator, self.value.denominator)

    def evaluate(self, env):
        return float(self.value)


@dataclass(frozen=True)
class Name(Expr):
    """A parameter, a coordinate-independent variable (t, i, n) or ``pi``."""

    name: str

    def symbols(self):
        return frozenset() if self.name in CONSTANTS else frozenset({self.name})

    def to_sympy(self, symbols):
        if self.name == "pi":
            import sympy

            return sympy.pi
        return symbols[self.name]

    def evaluate(self, env):
        if self.name == "pi":
            return math.pi
        return env[self.name]


@dataclass(frozen=True)
class Neg(Expr):
    operand: Expr

    def symbols(self):
        return self.operand.symbols()

    def to_sympy(self, symbols):
        return -self.operand.to_sympy(symbols)

    def evaluate(self, env):
        return -self.operand.evaluate(env)


@dataclass(frozen=True)
class BinOp(Expr):
    op: str
    left: Expr
    right: Expr

    def symbols(self):
        return self.left.symbols() | self.right.symbols()

    def to_sympy(self, symbols):
        import sympy

        a, b = self.left.to_sympy(symbols), self.right.to_sympy(symbols)
        if self.op == "+":
            return a + b
        if self.op == "-":
            return a - b
        if self.op == "*":
            return a * b
        if self.op == "/":
            return a / b
        if self.op == "**":
            return a**b
        return sympy.Mod(a, b)

    def evaluate(self, env):
        a, b = self.left.evaluate(env), self.right.evaluate(env)
        with np.errstate(all="ignore"):
            if self.op == "+":
                return a + b
            if self.op == "-":
                return a - b
            if self.op == "*":
                return a * b
            if self.op == "/":
                return np.divide(a, b)
            if self.op == "**":
                return np.power(a, b)
            return np.mod(a, b)


@dataclass(frozen=True)
class Call(Expr):
    func: str
    arg: Expr

    def symbols(self):
        return self.arg.symbols()

    def to_sympy(self, symbols):
        import sympy

        return getattr(sympy, self.func)(self.arg.to_sympy(symbols))

    def evaluate(self, env):
        with np.errstate(all="ignore"):
            return getattr(np, self.func)(self.arg.evaluate(env))


def _constant_value(node: Expr) -> Fraction | None:
    """The exact value of a tree made only of numbers, + - * /, else None."""
    if isinstance(node, Num):
        return node.value
    if isinstance(node, Neg):
        v = _constant_value(node.operand)
        return None if v is None else -v
    if isinstance(node, BinOp) and node.op in "+-*/":
        a, b = _constant_value(node.left), _constant_value(node.right)
        if a is None or b is None:
            return None
        if node.op == "+":
            return a + b
        if node.op == "-":
            return a - b
        if node.op == "*":
            return a * b
        return None if b == 0 else a / b
    return None


def parse_expression(
    text: object,
    allowed: frozenset[str] | set[str],
    *,
    file: str | None = None,
    key: str | None = None,
    functions: tuple[str, ...] = FUNCTIONS,
) -> Expr:
    """Parse untrusted scene text into an :class:`Expr`.

    Parameters
    ----------
    text : str or int or float
        The scene value. Numbers are accepted as they are.
    allowed : set of str
        Names the expression may use (parameters, and e.g. ``t``, ``i``, ``n``).
    file, key : str, optional
        Where the text came from, for error messages.
    functions : tuple of str
        Function names the expression may call.

    Raises
    ------
    SceneError
        Naming the file, key, the offending text and what is accepted.
    """

    def fail(why: str) -> SceneError:
        shown = text if isinstance(text, str) and len(text) <= 80 else (str(text)[:77] + "...")
        return SceneError(file, key, f"{shown!r}: {why}")

    if isinstance(text, bool):
        raise fail("expected an expression string or a number, not a boolean")
    if isinstance(text, (int, float)):
        if not math.isfinite(text) or abs(text) > MAX_LITERAL:
            raise fail("numbers must be finite")
        return Num(Fraction(repr(float(text))) if isinstance(text, float) else Fraction(text))
    if not isinstance(text, str):
        raise fail("expected an expression string or a number")
    if len(text) > MAX_LENGTH:
        raise fail(f"expression longer than {MAX_LENGTH} characters")
    if not text.isascii():
        raise fail("only ASCII characters are accepted (no look-alike letters)")
    if not text.strip():
        raise fail("empty expression")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        msg = getattr(exc, "msg", None) or type(exc).__name__
        raise fail(f"not a valid expression ({msg})") from None

    accepted = (
        f"numbers, the names {sorted(allowed) or '(none)'}, + - * / ** %, parentheses"
        + (f" and {', '.join(functions)}(...)" if functions else "")
        + (", pi")
    )
    count = 0

    def walk(node: ast.AST, depth: int) -> Expr:
        nonlocal count
        count += 1
        if count > MAX_NODES:
            raise fail(f"expression has more than {MAX_NODES} parts")
        if depth > MAX_DEPTH:
            raise fail(f"expression nested deeper than {MAX_DEPTH}")
        if isinstance(node, ast.Expression):
            return walk(node.body, depth + 1)
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise fail(f"{type(v).__name__} literals are not accepted; accepted: {accepted}")
            if isinstance(v, int) and abs(v) > MAX_LITERAL:
                raise fail("number too large")
            if isinstance(v, float) and (not math.isfinite(v) or abs(v) > MAX_LITERAL):
                raise fail("numbers must be finite")
            return Num(Fraction(repr(v)) if isinstance(v, float) else Fraction(v))
        if isinstance(node, ast.Name):
            if node.id in CONSTANTS:
                return Name(node.id)
            if node.id not in allowed:
                raise fail(f"unknown name {node.id!r}; accepted: {accepted}")
            return Name(node.id)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = walk(node.operand, depth + 1)
            return Neg(inner) if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            op = _BINOPS[type(node.op)]
            left, right = walk(node.left, depth + 1), walk(node.right, depth + 1)
            if op == "**":
                exponent = _constant_value(right)
                if exponent is None:
                    raise fail("an exponent must be a number (e.g. x**2, x**(1/2))")
                if abs(exponent) > MAX_EXPONENT or exponent.denominator > MAX_EXPONENT:
                    raise fail(f"exponent {exponent} out of range; accepted: |p| <= {MAX_EXPONENT}")
            return BinOp(op, left, right)
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name) or node.func.id not in functions:
                name = node.func.id if isinstance(node.func, ast.Name) else type(node.func).__name__
                raise fail(f"calls to {name!r} are not accepted; accepted functions: {', '.join(functions)}")
            if node.keywords or len(node.args) != 1 or isinstance(node.args[0], ast.Starred):
                raise fail(f"{node.func.id}() takes exactly one argument")
            return Call(node.func.id, walk(node.args[0], depth + 1))
        raise fail(f"{type(node).__name__} is not accepted; accepted: {accepted}")

    try:
        return walk(tree, 0)
    except RecursionError:
        raise fail("expression nested too deeply") from None
