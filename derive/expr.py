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
from fractions import Fraction


from .errors import SceneError, show
from .expr_tree import CONSTANTS, FUNCTIONS, RESERVED_FUNCTIONS, ARITHMETIC, BinOp, Call, Expr, Name, Neg, Num

#: Functions only springchain's own printed closed forms call (read back by derive.readback): a
#: parameter of that name and the function coexist there, as before.
READBACK_ONLY = ("acos",)

#: The chain index variables: ``q**i`` (a parameter to a power of them) is accepted.
INDEX_NAMES = frozenset({"i", "n"})
#: The other variables of scene expressions (time, a potential's extension): never a power's base.
VARIABLE_NAMES = frozenset({"t", "d"})

MAX_LENGTH = 500
MAX_NODES = 200
MAX_DEPTH = 24
MAX_EXPONENT = 16
MAX_TOTAL_EXPONENT = 64
MAX_LITERAL = 1e300
MAX_DIGITS = 10_000


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
        if node.op == "/":
            return None if b == 0 else a / b
        return ARITHMETIC[node.op](a, b)
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


def as_sympy(value):
    """A SymPy object from a SymPy object or a Python number, never from text: scene text reaches SymPy
    only through :func:`parse_expression`'s whitelist of syntax-tree nodes (a ``str`` raises TypeError)."""
    if isinstance(value, str):
        raise TypeError("text is not converted to SymPy here; parse it with parse_expression")
    import sympy as sp

    return sp.sympify(value, strict=True)


def accepted_form(allowed, functions: tuple[str, ...] = FUNCTIONS) -> str:
    """What an expression may contain, for messages."""
    names = ", ".join(sorted(allowed)) or "(none)"
    funcs = f", {' '.join(functions)} (one argument)" if functions else ""
    power = " (or q**i: a parameter to a power of the index)" if "i" in allowed else ""
    return f"numbers, the names {names}, pi, + - * / % and ** with a constant exponent{power}, ( ){funcs}"


def parse_expression(
    text: object,
    allowed: frozenset[str] | set[str],
    *,
    file: str | None = None,
    key: str | None = None,
    functions: tuple[str, ...] = FUNCTIONS,
    max_length: int = MAX_LENGTH,
    max_nodes: int = MAX_NODES,
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
    max_length, max_nodes : int
        Size limits (defaults :data:`MAX_LENGTH`, :data:`MAX_NODES`; reading back
        springchain's own printed closed forms allows longer text).

    Returns
    -------
    Expr

    Raises
    ------
    SceneError
        Naming the file, key, the offending text and what is accepted. No
        other exception escapes, whatever ``text`` is.
    """
    fail = _Fail(text, file, key, accepted_form(allowed, functions))
    if isinstance(text, bool):
        raise fail("a boolean, not an expression")
    if isinstance(text, (int, float)):
        return _literal(text, fail)
    if not isinstance(text, str):
        raise fail(f"a {type(text).__name__}, not an expression", "a number or an expression string")
    tree = _syntax_tree(text, max_length, fail)
    try:
        return _Walker(allowed, functions, max_nodes, fail).walk(tree, 0, 1.0)
    except (RecursionError, MemoryError):
        raise fail("nested too deeply", f"at most {MAX_DEPTH} levels of nesting") from None


class _Fail:
    """The :class:`SceneError` of one scene value: ``fail(why, hint)``; ``hint`` defaults to what
    an expression may contain, None leaves it out."""

    _ACCEPTED = object()

    def __init__(self, text: object, file: str | None, key: str | None, accepted: str):
        self.text, self.file, self.key, self.accepted = text, file, key, accepted

    def __call__(self, why: str, hint: str | None = _ACCEPTED) -> SceneError:
        hint = self.accepted if hint is self._ACCEPTED else hint
        return SceneError(self.file, self.key, f"{show(self.text)}: {why}" + (f"; accepted: {hint}" if hint else ""))


def _literal(value: int | float, fail: _Fail) -> Num:
    """A number given as a TOML number (not text)."""
    try:
        ok = math.isfinite(value) and abs(value) <= MAX_LITERAL
    except OverflowError:
        ok = False
    if not ok:
        raise fail("not a finite number", f"numbers up to {MAX_LITERAL:g} in size, or an expression")
    return Num(Fraction(repr(float(value))) if isinstance(value, float) else Fraction(value))


def _syntax_tree(text: str, max_length: int, fail: _Fail) -> ast.Expression:
    """Python's parse of the text after the checks on its size, characters and nesting."""
    if len(text) > max_length:
        raise fail(f"longer than {max_length} characters", f"expressions up to {max_length} characters")
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
            return ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError) as exc:
        msg = getattr(exc, "msg", None) or type(exc).__name__
        raise fail(f"not a valid expression ({msg})") from None


class _Walker:
    """Walks a syntax tree against the whitelist into :class:`Expr` nodes, counting parts and the
    exact digits its numbers need (``power``: the exponent the current subtree is raised to)."""

    def __init__(self, allowed, functions: tuple[str, ...], max_nodes: int, fail: _Fail):
        self.allowed, self.functions, self.max_nodes, self.fail = allowed, functions, max_nodes, fail
        self.count = 0
        self.digits = 0

    def walk(self, node: ast.AST, depth: int, power: float) -> Expr:
        fail = self.fail
        self.count += 1
        if self.count > self.max_nodes:
            raise fail(f"more than {self.max_nodes} parts", f"expressions of at most {self.max_nodes} parts")
        if depth > MAX_DEPTH:
            raise fail(f"nested deeper than {MAX_DEPTH} levels", f"at most {MAX_DEPTH} levels of nesting")
        if isinstance(node, ast.Expression):
            return self.walk(node.body, depth + 1, power)
        if isinstance(node, ast.Constant):
            return self._constant(node.value, power)
        if isinstance(node, ast.Name):
            return self._name(node.id)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = self.walk(node.operand, depth + 1, power)
            return Neg(inner) if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            return self._binop(_BINOPS[type(node.op)], node, depth, power)
        if isinstance(node, ast.Call):
            return self._call(node, depth, power)
        raise fail(f"{_describe(node)} not accepted")

    def _constant(self, v, power: float) -> Num:
        fail = self.fail
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            what = "..." if v is Ellipsis else type(v).__name__
            raise fail(f"{what} literals are not accepted")
        if isinstance(v, float) and not math.isfinite(v):
            raise fail("a number beyond floating-point range", f"numbers up to {MAX_LITERAL:g} in size")
        if abs(v) > MAX_LITERAL:
            raise fail("a number too large", f"numbers up to {MAX_LITERAL:g} in size")
        value = Fraction(repr(v)) if isinstance(v, float) else Fraction(v)
        self.digits += math.ceil(_digits(value) * power)
        if self.digits > MAX_DIGITS:
            raise fail("its numbers, with their powers, need more than "
                       f"{MAX_DIGITS} exact digits", "fewer or smaller literals")
        return Num(value)

    def _name(self, name: str) -> Name:
        if name in CONSTANTS:
            return Name(name)
        if name not in self.allowed:
            near = difflib.get_close_matches(name, sorted(self.allowed) + list(CONSTANTS), n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            if name in self.functions:
                raise self.fail(f"{name} must be called, as {name}(...)")
            raise self.fail(f"unknown name {name!r}{hint}")
        return Name(name)

    def _binop(self, op: str, node: ast.BinOp, depth: int, power: float) -> BinOp:
        fail = self.fail
        if op == "%":
            # a constant divisor only: SymPy's Mod with a symbolic divisor runs polynomial gcds
            # that can take unbounded time (e.g. 46 % exp(617175.67*exp(b)))
            left, right = self.walk(node.left, depth + 1, power), self.walk(node.right, depth + 1, power)
            divisor = _constant_value(right)
            if divisor is None or divisor == 0:
                raise fail("% needs a nonzero constant number on its right",
                           "a % p with p a nonzero number, e.g. i % 2")
            return BinOp(op, left, right)
        if op != "**":
            return BinOp(op, self.walk(node.left, depth + 1, power), self.walk(node.right, depth + 1, power))
        right = self.walk(node.right, depth + 1, power)
        exponent = _constant_value(right)
        if exponent is None:
            index = right.symbols()
            if index and index <= INDEX_NAMES and isinstance(node.left, ast.Name) and \
                    node.left.id not in INDEX_NAMES | VARIABLE_NAMES | set(CONSTANTS):
                # geometric growth along a chain, q**i: a parameter (never a number, whose exact
                # powers SymPy would compute digit by digit) to a power of the index; its value at
                # every index is range-checked by the loader
                return BinOp(op, self._name(node.left.id), right)
            raise fail("an exponent that is not a constant number",
                       "** with a constant exponent, e.g. x**2, x**(1/2), x**-1"
                       + (", or a parameter to a power of the index, e.g. q**i" if "i" in self.allowed else ""))
        if abs(exponent) > MAX_EXPONENT or exponent.denominator > MAX_EXPONENT:
            raise fail(f"exponent {exponent} out of range",
                       f"constant exponents p = a/b with |p| <= {MAX_EXPONENT}, b <= {MAX_EXPONENT}")
        total = power * max(1.0, float(abs(exponent)))
        if total > MAX_TOTAL_EXPONENT:
            raise fail(f"powers of powers reach exponent {total:g}",
                       f"nested exponents multiplying to at most {MAX_TOTAL_EXPONENT}")
        return BinOp(op, self.walk(node.left, depth + 1, total), right)

    def _call(self, node: ast.Call, depth: int, power: float) -> Call:
        fail, functions = self.fail, self.functions
        if not isinstance(node.func, ast.Name):
            raise fail(f"calling {_describe(node.func)} is not accepted",
                       f"calls of {', '.join(functions) or '(none)'} by name")
        if node.func.id not in functions:
            raise fail(f"calls to {node.func.id!r} are not accepted",
                       f"the functions {', '.join(functions) or '(none)'}")
        if node.func.id in self.allowed and node.func.id not in RESERVED_FUNCTIONS + READBACK_ONLY:
            # a parameter named log (tanh, cosh, sinh): the name is taken in this scene
            raise fail(f"{node.func.id!r} is a parameter of this scene, so {node.func.id}() cannot be "
                       "called", f"another name for the parameter {node.func.id!r}")
        if node.keywords or len(node.args) != 1 or isinstance(node.args[0], ast.Starred):
            raise fail(f"{node.func.id}() takes exactly one argument",
                       f"{node.func.id}(x) with one plain argument")
        return Call(node.func.id, self.walk(node.args[0], depth + 1, power))


def _describe(node: ast.AST) -> str:
    """A short name for a piece of syntax in messages."""
    if isinstance(node, (ast.BinOp, ast.UnaryOp)) and type(node.op) in _OPERATORS:
        return f"the operator {_OPERATORS[type(node.op)]}"
    if isinstance(node, ast.Name):
        return repr(node.id)
    return _DESCRIBE.get(type(node), type(node).__name__)


__all__ = ["Expr", "Num", "Name", "Neg", "BinOp", "Call", "parse_expression", "accepted_form",
           "FUNCTIONS", "CONSTANTS", "MAX_LENGTH", "MAX_NODES", "MAX_DEPTH", "MAX_EXPONENT"]
