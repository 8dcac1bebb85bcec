"""Safe expressions from untrusted scene text.

Scene files are untrusted input. An expression such as ``"3*m"`` or
``"F0*cos(Omega*t)"`` is parsed with :func:`ast.parse` and the resulting tree
is walked against a whitelist of node types; anything else (attribute access,
calls to names other than the allowed functions, subscripts, strings,
lambdas, comprehensions, f-strings, non-ASCII names, over-long or
over-deep input) is rejected before anything is evaluated.

Bounds keep every later step cheap: at most ``MAX_LENGTH`` characters,
``MAX_DEPTH`` levels of nesting (parentheses counted in the text, before the
parser sees it), ``MAX_NODES`` parts, exponents that are small constants
(``|p| <= MAX_EXPONENT``, powers of powers at most ``MAX_TOTAL_EXPONENT`` in
all), ``%`` only by a nonzero constant (``i % 2``), literals up to ``MAX_LITERAL`` and ``MAX_DIGITS`` digits of exact
numbers in all. ``9**9**9`` is refused by its form, never computed.

The result is a small immutable tree of :class:`Expr` nodes that knows
nothing of SymPy: :meth:`Expr.to_sympy` builds SymPy objects (SymPy is
imported lazily, and only from ``derive/``), :meth:`Expr.evaluate` computes a
NumPy value from a mapping of names to numbers or arrays, and
:meth:`Expr.evaluate_error` adds a bound on its rounding error (used to tell
a value from zero). Raw text is never handed to ``eval``, ``exec``,
``sympify`` or ``parse_expr``.
"""

from __future__ import annotations

import ast
import difflib
import math
import warnings
from dataclasses import dataclass
from fractions import Fraction
from typing import Mapping

import numpy as np

from .errors import SceneError, show

MAX_LENGTH = 500
MAX_NODES = 200
MAX_DEPTH = 24
MAX_EXPONENT = 16
MAX_TOTAL_EXPONENT = 64
MAX_LITERAL = 1e300
MAX_DIGITS = 10_000

#: Functions a scene expression may call, each with exactly one argument.
FUNCTIONS = ("cos", "exp", "sin", "sqrt")
#: Named constants a scene expression may use.
CONSTANTS = ("pi",)

_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**", ast.Mod: "%"}

#: What a rejected piece of syntax is called in messages.
_DESCRIBE = {
    ast.Attribute: "attribute access (a.b)",
    ast.Subscript: "subscripts (a[b])",
    ast.Lambda: "lambda",
    ast.IfExp: "conditional expressions (a if b else c)",
    ast.BoolOp: "boolean operators (and, or)",
    ast.Compare: "comparisons",
    ast.NamedExpr: "assignment expressions (:=)",
    ast.Starred: "starred arguments",
    ast.Tuple: "tuples",
    ast.List: "lists",
    ast.Dict: "dicts",
    ast.Set: "sets",
    ast.ListComp: "comprehensions",
    ast.SetComp: "comprehensions",
    ast.DictComp: "comprehensions",
    ast.GeneratorExp: "generator expressions",
    ast.JoinedStr: "f-strings",
    ast.FormattedValue: "f-strings",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slices",
}
_OPERATORS = {ast.BitXor: "^", ast.BitAnd: "&", ast.BitOr: "|", ast.LShift: "<<", ast.RShift: ">>",
              ast.FloorDiv: "//", ast.MatMult: "@", ast.Invert: "~", ast.Not: "not"}

#: Relative rounding of one floating-point operation (with a margin for libm's sin, cos, exp).
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
            if self.func in ("sin", "cos"):  # Lipschitz 1, plus libm's rounding
                e = ea + _U * (1.0 + _abs(v)) + _ETA
            elif self.func == "exp":
                e = _abs(v) * np.expm1(ea) + 2 * _U * _abs(v) + _ETA
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


def _digits(value: Fraction) -> int:
    """Decimal digits of an exact number (numerator and denominator)."""
    return len(str(abs(value.numerator))) + len(str(value.denominator))


def _nesting(text: str) -> int:
    """Deepest bracket nesting in the text (any of ( [ {)."""
    depth = deepest = 0
    for ch in text:
        if ch in "([{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in ")]}":
            depth -= 1
    return deepest


def accepted_form(allowed, functions: tuple[str, ...] = FUNCTIONS) -> str:
    """What an expression may contain, for messages."""
    names = ", ".join(sorted(allowed)) or "(none)"
    funcs = f", {' '.join(functions)} (one argument)" if functions else ""
    return f"numbers, the names {names}, pi, + - * / % and ** with a constant exponent, ( ){funcs}"


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

    Returns
    -------
    Expr

    Raises
    ------
    SceneError
        Naming the file, key, the offending text and what is accepted. No
        other exception escapes, whatever ``text`` is.
    """
    accepted = accepted_form(allowed, functions)

    def fail(why: str, hint: str | None = accepted) -> SceneError:
        return SceneError(file, key, f"{show(text)}: {why}" + (f"; accepted: {hint}" if hint else ""))

    if isinstance(text, bool):
        raise fail("a boolean, not an expression")
    if isinstance(text, (int, float)):
        try:
            ok = math.isfinite(text) and abs(text) <= MAX_LITERAL
        except OverflowError:
            ok = False
        if not ok:
            raise fail("not a finite number", f"numbers up to {MAX_LITERAL:g} in size, or an expression")
        return Num(Fraction(repr(float(text))) if isinstance(text, float) else Fraction(text))
    if not isinstance(text, str):
        raise fail(f"a {type(text).__name__}, not an expression", "a number or an expression string")
    if len(text) > MAX_LENGTH:
        raise fail(f"longer than {MAX_LENGTH} characters", f"expressions up to {MAX_LENGTH} characters")
    if not text.isascii():
        bad = next(ch for ch in text if not ch.isascii())
        raise fail(f"non-ASCII character {bad!r} (look-alike letters are refused)", "ASCII text only")
    if "\x00" in text:
        raise fail("contains a NUL character", "printable ASCII text")
    if not text.strip():
        raise fail("empty expression")
    if _nesting(text) > MAX_DEPTH:
        raise fail(f"nested deeper than {MAX_DEPTH} levels", f"at most {MAX_DEPTH} levels of parentheses")
    try:
        with warnings.catch_warnings():  # e.g. SyntaxWarning on "1or a": never a second line on stderr
            warnings.simplefilter("ignore")
            tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError) as exc:
        msg = getattr(exc, "msg", None) or type(exc).__name__
        raise fail(f"not a valid expression ({msg})") from None

    count = 0
    digits = 0

    def walk(node: ast.AST, depth: int, power: float) -> Expr:
        nonlocal count, digits
        count += 1
        if count > MAX_NODES:
            raise fail(f"more than {MAX_NODES} parts", f"expressions of at most {MAX_NODES} parts")
        if depth > MAX_DEPTH:
            raise fail(f"nested deeper than {MAX_DEPTH} levels", f"at most {MAX_DEPTH} levels of nesting")
        if isinstance(node, ast.Expression):
            return walk(node.body, depth + 1, power)
        if isinstance(node, ast.Constant):
            v = node.value
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                what = "..." if v is Ellipsis else type(v).__name__
                raise fail(f"{what} literals are not accepted")
            if isinstance(v, float) and not math.isfinite(v):
                raise fail("a number beyond floating-point range", f"numbers up to {MAX_LITERAL:g} in size")
            if abs(v) > MAX_LITERAL:
                raise fail("a number too large", f"numbers up to {MAX_LITERAL:g} in size")
            value = Fraction(repr(v)) if isinstance(v, float) else Fraction(v)
            digits += math.ceil(_digits(value) * power)
            if digits > MAX_DIGITS:
                raise fail("its numbers, with their powers, need more than "
                           f"{MAX_DIGITS} exact digits", "fewer or smaller literals")
            return Num(value)
        if isinstance(node, ast.Name):
            if node.id in CONSTANTS:
                return Name(node.id)
            if node.id not in allowed:
                near = difflib.get_close_matches(node.id, sorted(allowed) + list(CONSTANTS), n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else ""
                if node.id in functions:
                    raise fail(f"{node.id} must be called, as {node.id}(...)")
                raise fail(f"unknown name {node.id!r}{hint}")
            return Name(node.id)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = walk(node.operand, depth + 1, power)
            return Neg(inner) if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            op = _BINOPS[type(node.op)]
            if op == "%":
                # a constant divisor only: SymPy's Mod with a symbolic divisor runs polynomial gcds
                # that can take unbounded time (e.g. 46 % exp(617175.67*exp(b)))
                left, right = walk(node.left, depth + 1, power), walk(node.right, depth + 1, power)
                divisor = _constant_value(right)
                if divisor is None or divisor == 0:
                    raise fail("% needs a nonzero constant number on its right",
                               "a % p with p a nonzero number, e.g. i % 2")
                return BinOp(op, left, right)
            if op != "**":
                return BinOp(op, walk(node.left, depth + 1, power), walk(node.right, depth + 1, power))
            right = walk(node.right, depth + 1, power)
            exponent = _constant_value(right)
            if exponent is None:
                raise fail("an exponent that is not a constant number",
                           "** with a constant exponent, e.g. x**2, x**(1/2), x**-1")
            if abs(exponent) > MAX_EXPONENT or exponent.denominator > MAX_EXPONENT:
                raise fail(f"exponent {exponent} out of range",
                           f"constant exponents p = a/b with |p| <= {MAX_EXPONENT}, b <= {MAX_EXPONENT}")
            total = power * max(1.0, float(abs(exponent)))
            if total > MAX_TOTAL_EXPONENT:
                raise fail(f"powers of powers reach exponent {total:g}",
                           f"nested exponents multiplying to at most {MAX_TOTAL_EXPONENT}")
            return BinOp(op, walk(node.left, depth + 1, total), right)
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name):
                raise fail(f"calling {_describe(node.func)} is not accepted",
                           f"calls of {', '.join(functions) or '(none)'} by name")
            if node.func.id not in functions:
                raise fail(f"calls to {node.func.id!r} are not accepted",
                           f"the functions {', '.join(functions) or '(none)'}")
            if node.keywords or len(node.args) != 1 or isinstance(node.args[0], ast.Starred):
                raise fail(f"{node.func.id}() takes exactly one argument",
                           f"{node.func.id}(x) with one plain argument")
            return Call(node.func.id, walk(node.args[0], depth + 1, power))
        raise fail(f"{_describe(node)} not accepted")

    try:
        return walk(tree, 0, 1.0)
    except (RecursionError, MemoryError):
        raise fail("nested too deeply", f"at most {MAX_DEPTH} levels of nesting") from None


def _describe(node: ast.AST) -> str:
    """A short name for a piece of syntax in messages."""
    if isinstance(node, (ast.BinOp, ast.UnaryOp)) and type(node.op) in _OPERATORS:
        return f"the operator {_OPERATORS[type(node.op)]}"
    if isinstance(node, ast.Name):
        return repr(node.id)
    return _DESCRIBE.get(type(node), type(node).__name__)


__all__ = ["Expr", "Num", "Name", "Neg", "BinOp", "Call", "parse_expression", "accepted_form",
           "FUNCTIONS", "CONSTANTS", "MAX_LENGTH", "MAX_NODES", "MAX_DEPTH", "MAX_EXPONENT"]
