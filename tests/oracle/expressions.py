"""The scene expression language evaluated in mpmath, written from the README alone (no springchain code).

An expression (``"k*d**2/2 + beta*d**4/4"``, ``"F0*cos(W*t)"``, ``"m*(1 + i % 2)"``) is parsed by
``ast`` and walked over the README's whitelist: numbers, names, ``+ - * / **``, ``%`` by a constant,
``sqrt sin cos exp log tanh cosh sinh`` and ``pi``. Values are of three kinds, so one walker serves
every use:

* ``mpf`` — a number (parameters, masses, spring constants, chain entries at an index ``i``);
* :class:`Jet` — a truncated Taylor series in the spring extension ``d`` about a point, giving V(d),
  V'(d), V''(d), ... exactly (no finite differences);
* :class:`Lin` and :class:`Harm` — functions of time ``t``: ``a + b·t`` (only as the argument of
  ``sin``/``cos``) and finite sums ``Σ c_w e^{i w t}`` (constants and harmonics: the forcings with a
  closed-form response). Anything else of ``t`` raises :class:`NotClosedForm`.

Literals are read from their text as exact decimals (``"2e-70"`` is 2·10⁻⁷⁰ at the working precision).
"""

from __future__ import annotations

import ast
import functools

from mpmath import mp

FUNCTIONS = ("sqrt", "sin", "cos", "exp", "log", "tanh", "cosh", "sinh")


class ExpressionError(ValueError):
    """Outside the expression language, or a value that is not a finite real number."""


class NotClosedForm(Exception):
    """A time function outside constants and harmonics (its response has no closed form here)."""


_ALLOWED = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Constant, ast.Load,
            ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.USub, ast.UAdd)


def parse(text):
    """``(tree, source)`` of an expression given as TOML text or a number (parsed once per text)."""
    return _parse(text if not isinstance(text, float) else ("float", text))


@functools.lru_cache(maxsize=4096)
def _parse(text):
    if isinstance(text, tuple):
        text = text[1]
    if isinstance(text, bool):
        raise ExpressionError(f"{text!r}: a boolean")
    if isinstance(text, (int, float)):
        text = repr(text) if isinstance(text, int) else repr(float(text))
    if not isinstance(text, str):
        raise ExpressionError(f"{text!r}: not an expression")
    src = text.strip()
    try:
        tree = ast.parse(src, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"{text!r}: {exc.msg}") from None
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED):
            raise ExpressionError(f"{text!r}: {type(node).__name__} is not in the language")
        if isinstance(node, ast.Call) and (not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS
                                           or len(node.args) != 1 or node.keywords):
            raise ExpressionError(f"{text!r}: only one-argument calls of {', '.join(FUNCTIONS)}")
        if isinstance(node, ast.Constant) and (isinstance(node.value, bool)
                                               or not isinstance(node.value, (int, float))):
            raise ExpressionError(f"{text!r}: constant {node.value!r}")
    return tree.body, src


def names(text) -> set[str]:
    """Every name an expression uses (functions excluded)."""
    tree, _ = parse(text)
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and not (node.id in FUNCTIONS and _is_called(tree, node)):
            out.add(node.id)
    return out


def _is_called(tree, name_node) -> bool:
    return any(isinstance(n, ast.Call) and n.func is name_node for n in ast.walk(tree))


def evaluate(text, env: dict):
    """The value of ``text`` with the names of ``env`` (mpf, :class:`Jet`, :class:`Lin` or :class:`Harm`)."""
    tree, src = parse(text)
    return _Walker(src, env).visit(tree)


class _Walker:
    def __init__(self, src: str, env: dict):
        self.src, self.env = src, env

    def visit(self, node):
        if isinstance(node, ast.Constant):
            seg = ast.get_source_segment(self.src, node)
            return mp.mpf(seg.replace("_", "")) if seg else mp.mpf(node.value)
        if isinstance(node, ast.Name):
            if node.id == "pi" and "pi" not in self.env:
                return +mp.pi
            if node.id not in self.env:
                raise ExpressionError(f"{self.src!r}: unknown name {node.id!r}")
            return self.env[node.id]
        if isinstance(node, ast.UnaryOp):
            v = self.visit(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.BinOp):
            a, b = self.visit(node.left), self.visit(node.right)
            op = type(node.op)
            if op is ast.Add:
                return a + b
            if op is ast.Sub:
                return a - b
            if op is ast.Mult:
                return a * b
            if op is ast.Div:
                if _is_number(b) and b == 0:
                    raise ExpressionError(f"{self.src!r}: division by zero")
                return a / b
            if op is ast.Pow:
                return power(a, b, self.src)
            if op is ast.Mod:
                if not (_is_number(a) and _is_number(b)) or b == 0:
                    raise ExpressionError(f"{self.src!r}: % needs numbers and a nonzero divisor")
                return a - b * mp.floor(a / b)
        if isinstance(node, ast.Call):
            return function(node.func.id, self.visit(node.args[0]), self.src)
        raise ExpressionError(f"{self.src!r}: {ast.dump(node)}")


def _is_number(v) -> bool:
    return isinstance(v, (mp.mpf, int, float))


def _check_real(v, src: str):
    if not mp.isfinite(v):
        raise ExpressionError(f"{src!r}: not finite")
    return v


def power(a, b, src: str = ""):
    if not _is_number(b):
        raise ExpressionError(f"{src!r}: an exponent that is not a constant")
    integer = b == mp.floor(b)
    if isinstance(a, (Jet, Harm, Lin)):
        if isinstance(a, Lin):
            a = a.as_harm()
        if integer and b >= 0:
            out = a.one()
            for _ in range(int(b)):
                out = out * a
            return out
        if isinstance(a, Harm):
            return Harm.constant(power(a.constant_value(), b, src))
        if integer:
            return 1 / power(a, -b, src)
        return a.compose(_power_derivatives(a.c[0], b, src))
    if a < 0 and not integer:
        raise ExpressionError(f"{src!r}: a negative number to a fractional power")
    if a == 0 and b < 0:
        raise ExpressionError(f"{src!r}: 0 to a negative power")
    return _check_real(mp.power(a, b), src)


def _power_derivatives(c0, p, src: str, order: int = 8):
    if c0 <= 0:
        raise ExpressionError(f"{src!r}: a power of a non-positive value")
    out, coef = [], mp.mpf(1)
    for k in range(order + 1):
        out.append(coef * mp.power(c0, p - k))
        coef *= p - k
    return out


def _derivatives(name: str, c0, src: str, order: int):
    """g(c0), g'(c0), ..., g^(order)(c0) of a whitelisted function."""
    if name == "exp":
        e = mp.exp(c0)
        return [e] * (order + 1)
    if name in ("sin", "cos"):
        s, c = mp.sin(c0), mp.cos(c0)
        cyc = [s, c, -s, -c] if name == "sin" else [c, -s, -c, s]
        return [cyc[k % 4] for k in range(order + 1)]
    if name in ("sinh", "cosh"):
        s, c = mp.sinh(c0), mp.cosh(c0)
        cyc = [s, c] if name == "sinh" else [c, s]
        return [cyc[k % 2] for k in range(order + 1)]
    if name == "log":
        if c0 <= 0:
            raise ExpressionError(f"{src!r}: log of a non-positive value")
        return [mp.log(c0)] + [(-1) ** (k - 1) * mp.factorial(k - 1) / c0**k for k in range(1, order + 1)]
    if name == "sqrt":
        return _power_derivatives(c0, mp.mpf(1) / 2, src, order)
    raise ExpressionError(f"{src!r}: {name}")


def function(name: str, x, src: str = ""):
    """A whitelisted function of a number, a :class:`Jet` or a time function."""
    if isinstance(x, Lin):
        if x.b == 0:
            return function(name, x.a, src)
        if name in ("sin", "cos"):
            return Harm.sincos(name, x.a, x.b)
        raise NotClosedForm(f"{name} of a function of t")
    if isinstance(x, Harm):
        return Harm.constant(function(name, x.constant_value(), src))
    if isinstance(x, Jet):
        if name == "tanh":
            return function("sinh", x, src) / function("cosh", x, src)
        return x.compose(_derivatives(name, x.c[0], src, x.order))
    if name == "tanh":
        return mp.tanh(x)
    if name == "sqrt":
        if x < 0:
            raise ExpressionError(f"{src!r}: sqrt of a negative value")
        return mp.sqrt(x)
    if name == "log" and x <= 0:
        raise ExpressionError(f"{src!r}: log of a non-positive value")
    return _check_real(getattr(mp, name)(x), src)


# -- Taylor jets in the extension d ---------------------------------------------------------------------
class Jet:
    """A truncated Taylor series ``Σ c_k h^k`` of a function at ``d0 + h`` (``c_k = f^(k)(d0)/k!``)."""

    __slots__ = ("c",)

    def __init__(self, c):
        self.c = list(c)

    @property
    def order(self) -> int:
        return len(self.c) - 1

    @classmethod
    def variable(cls, d0, order: int = 3) -> "Jet":
        return cls([mp.mpf(d0), mp.mpf(1)] + [mp.mpf(0)] * (order - 1))

    def derivative(self, k: int):
        """f^(k)(d0)."""
        return self.c[k] * mp.factorial(k)

    def one(self) -> "Jet":
        return Jet([mp.mpf(1)] + [mp.mpf(0)] * self.order)

    def _lift(self, other) -> "Jet":
        if isinstance(other, Jet):
            return other
        if isinstance(other, (Harm, Lin)):
            raise ExpressionError("an expression of both d and t")
        return Jet([mp.mpf(other)] + [mp.mpf(0)] * self.order)

    def __add__(self, o):
        o = self._lift(o)
        return Jet([a + b for a, b in zip(self.c, o.c)])

    __radd__ = __add__

    def __neg__(self):
        return Jet([-a for a in self.c])

    def __pos__(self):
        return self

    def __sub__(self, o):
        return self + (-self._lift(o))

    def __rsub__(self, o):
        return self._lift(o) - self

    def __mul__(self, o):
        o = self._lift(o)
        K = self.order
        return Jet([mp.fsum(self.c[j] * o.c[k - j] for j in range(k + 1)) for k in range(K + 1)])

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = self._lift(o)
        return self * o.compose(_power_derivatives_any(o.c[0], -1, o.order))

    def __rtruediv__(self, o):
        return self._lift(o) / self

    def compose(self, derivs) -> "Jet":
        """g(self) from g's derivatives at self's constant term."""
        K = self.order
        u = Jet([mp.mpf(0)] + self.c[1:])
        out = Jet([derivs[0]] + [mp.mpf(0)] * K)
        term = self.one()
        for k in range(1, K + 1):
            term = term * u
            out = out + term * (derivs[k] / mp.factorial(k))
        return out


def _power_derivatives_any(c0, p: int, order: int):
    """Derivatives of x**p for an integer p (any sign of x, x != 0)."""
    if c0 == 0:
        raise ExpressionError("division by zero")
    out, coef = [], mp.mpf(1)
    for k in range(order + 1):
        out.append(coef * c0 ** (p - k))
        coef *= p - k
    return out


# -- functions of time --------------------------------------------------------------------------------
class Lin:
    """``a + b·t`` (``t`` itself, and the arguments of sin/cos)."""

    __slots__ = ("a", "b")

    def __init__(self, a, b):
        self.a, self.b = mp.mpf(a), mp.mpf(b)

    def as_harm(self) -> "Harm":
        if self.b != 0:
            raise NotClosedForm("t outside sin/cos (a ramp)")
        return Harm.constant(self.a)

    def one(self):
        return Harm.constant(1)

    def __add__(self, o):
        if isinstance(o, Lin):
            return Lin(self.a + o.a, self.b + o.b)
        if isinstance(o, Harm):
            return self.as_harm() + o
        return Lin(self.a + o, self.b)

    __radd__ = __add__

    def __neg__(self):
        return Lin(-self.a, -self.b)

    def __pos__(self):
        return self

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if isinstance(o, (Lin, Harm)):
            if isinstance(o, Lin) and o.b == 0:
                return self * o.a
            if isinstance(o, Harm) and o.is_constant():
                return self * o.constant_value()
            if self.b == 0:
                return o * self.a
            raise NotClosedForm("t times a function of t")
        return Lin(self.a * o, self.b * o)

    __rmul__ = __mul__

    def __truediv__(self, o):
        if isinstance(o, (Lin, Harm)):
            raise NotClosedForm("division by a function of t")
        return Lin(self.a / o, self.b / o)

    def __rtruediv__(self, o):
        if self.b == 0:
            return o / self.a
        raise NotClosedForm("division by a function of t")


class Harm:
    """A real function ``Σ c_w e^{i w t}`` (a dict w -> complex c, conjugate-symmetric): constants and harmonics."""

    __slots__ = ("terms",)

    def __init__(self, terms: dict):
        self.terms = {w: c for w, c in terms.items() if c != 0}

    @classmethod
    def constant(cls, value) -> "Harm":
        return cls({mp.mpf(0): mp.mpc(value)})

    @classmethod
    def sincos(cls, name: str, a, b) -> "Harm":
        """sin/cos(a + b t) = (e^{i(a + bt)} ± e^{-i(a + bt)}) / 2 (or 2i)."""
        e = mp.expj(a)
        if name == "cos":
            return cls({b: e / 2}) + cls({-b: mp.conj(e) / 2})
        return cls({b: e / mp.mpc(0, 2)}) + cls({-b: -mp.conj(e) / mp.mpc(0, 2)})

    def one(self):
        return Harm.constant(1)

    def is_constant(self) -> bool:
        return all(w == 0 for w in self.terms)

    def constant_value(self):
        if not self.is_constant():
            raise NotClosedForm("a function of a harmonic (not a sum of harmonics)")
        return mp.re(self.terms.get(mp.mpf(0), mp.mpc(0)))

    def _lift(self, o) -> "Harm":
        if isinstance(o, Harm):
            return o
        if isinstance(o, Lin):
            return o.as_harm()
        if isinstance(o, Jet):
            raise ExpressionError("an expression of both d and t")
        return Harm.constant(o)

    @staticmethod
    def _key(terms: dict, w):
        """An existing frequency equal to ``w`` up to rounding (W + W against 2*W), else ``w``."""
        for k in terms:
            if abs(k - w) <= mp.mpf(10) ** (-mp.dps + 8) * max(abs(k), abs(w), 1):
                return k
        return w

    def __add__(self, o):
        o = self._lift(o)
        out = dict(self.terms)
        for w, c in o.terms.items():
            k = self._key(out, w)
            out[k] = out.get(k, 0) + c
        return Harm(out)

    __radd__ = __add__

    def __neg__(self):
        return Harm({w: -c for w, c in self.terms.items()})

    def __pos__(self):
        return self

    def __sub__(self, o):
        return self + (-self._lift(o))

    def __rsub__(self, o):
        return self._lift(o) - self

    def __mul__(self, o):
        o = self._lift(o)
        out: dict = {}
        for w1, c1 in self.terms.items():
            for w2, c2 in o.terms.items():
                k = self._key(out, w1 + w2)
                out[k] = out.get(k, 0) + c1 * c2
        return Harm(out)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = self._lift(o)
        return self * (1 / o.constant_value())

    def __rtruediv__(self, o):
        return self._lift(o) * (1 / self.constant_value())

    def value(self, t):
        """The (real) value at time t."""
        return mp.re(mp.fsum(c * mp.expj(w * t) for w, c in self.terms.items())) if self.terms else mp.mpf(0)


def as_harm(v) -> Harm:
    """A time function (or a number) as a :class:`Harm`."""
    if isinstance(v, Harm):
        return v
    if isinstance(v, Lin):
        return v.as_harm()
    if isinstance(v, Jet):
        raise ExpressionError("a function of d where a function of t was expected")
    return Harm.constant(v)


__all__ = ["parse", "names", "evaluate", "function", "power", "Jet", "Lin", "Harm", "as_harm",
           "ExpressionError", "NotClosedForm", "FUNCTIONS"]
