"""The immutable expression tree of scene expressions (:class:`Expr` and its nodes).

Built only by :func:`springchain.derive.expr.parse_expression` from whitelisted syntax; knows nothing of
SymPy at import time: :meth:`Expr.to_sympy` builds SymPy objects (imported lazily),
:meth:`Expr.evaluate` computes a NumPy value from a mapping of names to numbers or arrays, and
:meth:`Expr.evaluate_error` adds a bound on its rounding error (used to tell a value from zero).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from fractions import Fraction
from typing import Mapping

import numpy as np

#: Functions a scene expression may call, each with exactly one argument.
FUNCTIONS = ("cos", "cosh", "exp", "log", "sin", "sinh", "sqrt", "tanh")
#: The functions every scene could call before potentials came (reserved as parameter names); the
#: later ones (log, tanh, cosh, sinh) are not reserved: a scene may still have a parameter ``log``,
#: it just cannot call log() then (see :func:`~springchain.derive.expr.parse_expression`).
RESERVED_FUNCTIONS = ("cos", "exp", "sin", "sqrt")
#: Named constants a scene expression may use.
CONSTANTS = ("pi",)


#: The operators that mean the same on exact fractions, SymPy objects and floats.
ARITHMETIC = {"+": operator.add, "-": operator.sub, "*": operator.mul}
#: Every binary operator on floats and arrays (warnings silenced by the caller).
_NUMPY_OPS = {**ARITHMETIC, "/": np.divide, "**": np.power, "%": np.mod}

_U = 2.0**-52
#: Absolute rounding in the subnormal range (the smallest positive float).
_ETA = 2.0**-1074
#: |float(pi) - pi|
_PI_ERROR = 1.2246467991473532e-16


def _abs(x):
    return np.abs(x)


@dataclass(frozen=True)
class Expr:
    """Base class of the parsed expression tree."""

    def symbols(self) -> frozenset[str]:
        """Names of the free variables (parameters, ``t``, ``i``, ``n``) used."""
        return frozenset()

    def numbers(self) -> tuple[Fraction, ...]:
        """The exact values of the number literals written in the expression, in reading order."""
        return ()

    def to_sympy(self, symbols: Mapping[str, object]):  # pragma: no cover - abstract
        """The SymPy expression, with ``symbols`` mapping each name to a SymPy symbol."""
        raise NotImplementedError

    def evaluate(self, env: Mapping[str, object]):  # pragma: no cover - abstract
        """The value for ``env`` (names to floats or arrays); broadcasts like NumPy."""
        raise NotImplementedError

    def evaluate_error(self, env: Mapping[str, object]):  # pragma: no cover - abstract
        """``(value, bound)``: the value in floating point and a bound on its
        distance to the exact value of the expression at the same inputs
        (first-order forward error analysis; inputs in ``env`` count as exact).
        The bound is ``inf`` where it cannot be given (e.g. dividing by a
        value that may be zero)."""
        raise NotImplementedError


@dataclass(frozen=True)
class Num(Expr):
    """A finite number literal, kept exact as a fraction of its decimal text."""

    value: Fraction

    def numbers(self):
        return (self.value,)

    def to_sympy(self, symbols):
        import sympy

        return sympy.Rational(self.value.numerator, self.value.denominator)

    def evaluate(self, env):
        return float(self.value)

    def evaluate_error(self, env):
        v = float(self.value)
        return v, float(abs(Fraction(v) - self.value))


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

    def evaluate_error(self, env):
        if self.name == "pi":
            return math.pi, _PI_ERROR
        return env[self.name], 0.0


@dataclass(frozen=True)
class Neg(Expr):
    operand: Expr

    def symbols(self):
        return self.operand.symbols()

    def numbers(self):
        return self.operand.numbers()

    def to_sympy(self, symbols):
        return -self.operand.to_sympy(symbols)

    def evaluate(self, env):
        return -self.operand.evaluate(env)

    def evaluate_error(self, env):
        v, e = self.operand.evaluate_error(env)
        return -v, e


@dataclass(frozen=True)
class BinOp(Expr):
    op: str
    left: Expr
    right: Expr

    def symbols(self):
        return self.left.symbols() | self.right.symbols()

    def numbers(self):
        return self.left.numbers() + self.right.numbers()

    def to_sympy(self, symbols):
        import sympy

        a, b = self.left.to_sympy(symbols), self.right.to_sympy(symbols)
        return {**ARITHMETIC, "/": operator.truediv, "**": operator.pow, "%": sympy.Mod}[self.op](a, b)

    def evaluate(self, env):
        a, b = self.left.evaluate(env), self.right.evaluate(env)
        with np.errstate(all="ignore"):
            return _NUMPY_OPS[self.op](a, b)

    def evaluate_error(self, env):
        a, ea = self.left.evaluate_error(env)
        b, eb = self.right.evaluate_error(env)
        with np.errstate(all="ignore"):
            a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            if self.op in "+-":
                v = a + b if self.op == "+" else a - b
                e = ea + eb
            elif self.op == "*":
                v = a * b
                e = _abs(a) * eb + _abs(b) * ea + ea * eb
            elif self.op == "/":
                v = np.divide(a, b)
                # |a/b - (a+da)/(b+db)| <= (|a/b| rb + ea/|b|) / (1 - rb) with rb = eb/|b|, written
                # with ratios so that nothing underflows for subnormal a, b
                rb = np.divide(eb, _abs(b))
                e = np.where(rb < 1, (_abs(v) * rb + np.divide(ea, _abs(b))) / (1 - rb), np.inf)
            elif self.op == "**":
                v = np.power(a, b)
                da = _abs(b) * np.power(_abs(a), b - 1.0)  # d/da a**b
                db = _abs(v * np.log(_abs(a)))  # d/db a**b
                whole = b == np.round(b)
                e = np.where(whole | (ea == 0) | (_abs(a) > ea), 0.0, np.inf)
                e = e + _times(da, ea) + _times(db, eb)
            else:  # a mod b: continuous except where a/b crosses a whole number
                v = np.mod(a, b)
                q = np.divide(a, b)
                e = ea + eb * (_abs(q) + 1.0)
                # near a jump, neither rounding nor SymPy (which must decide floor(a/b)) can say
                # on which side the exact value lies
                jump = (e > 0) & (_abs(q - np.round(q)) * _abs(b) <= e + _U * _abs(a))
                e = np.where(jump | (_abs(b) <= eb), np.inf, e)
            e = e + _U * _abs(v) + _ETA
            if self.op != "**":  # whole numbers below 2**53 combine exactly (e.g. (i + 1) % 2)
                exact = (ea == 0) & (eb == 0) & _whole(a) & _whole(b) & _whole(v)
                if self.op == "/":
                    exact = exact & (v * b == a)
                e = np.where(exact, 0.0, e)
        return _scalar(v), _bound(e)


@dataclass(frozen=True)
class Call(Expr):
    func: str
    arg: Expr

    def symbols(self):
        return self.arg.symbols()

    def numbers(self):
        return self.arg.numbers()

    def to_sympy(self, symbols):
        import sympy

        return getattr(sympy, self.func)(self.arg.to_sympy(symbols))

    def evaluate(self, env):
        with np.errstate(all="ignore"):
            return getattr(np, self.func)(self.arg.evaluate(env))

    def evaluate_error(self, env):
        a, ea = self.arg.evaluate_error(env)
        with np.errstate(all="ignore"):
            a = np.asarray(a, dtype=float)
            v = getattr(np, self.func)(a)
            if self.func in ("sin", "cos", "tanh"):  # Lipschitz 1, plus libm's rounding
                e = ea + _U * (1.0 + _abs(v)) + _ETA
            elif self.func == "exp":
                e = _abs(v) * np.expm1(ea) + 2 * _U * _abs(v) + _ETA
            elif self.func in ("sinh", "cosh"):  # |derivative| <= cosh(|a| + ea) on the interval
                e = _times(np.cosh(_abs(a) + ea), ea) + 2 * _U * _abs(v) + _ETA
            elif self.func == "log":  # |log a - log(a - ea)| <= ea / (a - ea) for a > ea > 0
                e = np.where(a > ea, np.divide(ea, a - ea), np.inf) + 2 * _U * _abs(v) + _ETA
            else:  # sqrt(a) - sqrt(a - ea) <= ea / (sqrt(a) + sqrt(a - ea))
                e = np.where(a > ea, ea / (np.sqrt(_abs(a)) + np.sqrt(np.maximum(a - ea, 0.0))),
                             np.sqrt(_abs(a) + ea))
                e = e + _U * _abs(v) + _ETA
        return _scalar(v), _bound(e)


def _whole(x):
    """Whether x is a whole number that float64 holds exactly."""
    return (x == np.round(x)) & (_abs(x) <= 2.0**53)


def _times(derivative, error):
    """``derivative * error`` with 0 where the error is 0 and inf where it cannot be bounded."""
    prod = np.nan_to_num(np.asarray(derivative) * error, nan=np.inf)
    return np.where(np.asarray(error) == 0, 0.0, prod)


def _bound(e):
    """An error bound: never nan (an unknown bound is inf)."""
    return _scalar(np.nan_to_num(np.asarray(e, dtype=float), nan=np.inf, posinf=np.inf))


def _scalar(x):
    x = np.asarray(x, dtype=float)
    return float(x) if x.ndim == 0 else x
