"""A SymPy expression as an mpmath function, without generating source code.

``sympy.lambdify(..., modules="mpmath")`` prints the expression to Python source and ``exec``\\ s it,
for every closed form a report evaluates (a mode's ω², shape entries, Γ): 8 ms per expression on 283
closed forms of the test suite's scenes, half the time :func:`derive.accurate.value` spent on them.
:func:`mp_function` walks the tree once into nested closures instead (0.2 ms) that do the same mpmath
operations lambdify's printer writes: sequential sums and products, ``mpmath.sqrt`` for square roots,
exact integers, rationals as ``mpf(p)/q`` at the working precision. Expressions with a node it does not
know fall back to lambdify. Used by :mod:`derive.accurate` and by :mod:`derive.equilibrium` (V, V', V''
of spring potentials at the equilibrium, in mpmath).
"""

from __future__ import annotations

from typing import Callable

import mpmath
import sympy as sp

#: SymPy function classes and the mpmath functions lambdify's mpmath printer maps them to.
_FUNCTIONS = {
    sp.cos: mpmath.cos, sp.sin: mpmath.sin, sp.tan: mpmath.tan, sp.acos: mpmath.acos, sp.asin: mpmath.asin,
    sp.atan: mpmath.atan, sp.cosh: mpmath.cosh, sp.sinh: mpmath.sinh, sp.tanh: mpmath.tanh,
    sp.exp: mpmath.exp, sp.log: mpmath.log, sp.re: mpmath.re, sp.im: mpmath.im, sp.Abs: abs,
    sp.atan2: mpmath.atan2, sp.conjugate: mpmath.conj,
}

_Node = Callable[[list], object]


class _Unknown(Exception):
    """A node the walker does not translate (the caller falls back to lambdify)."""


def _const(value) -> _Node:
    return lambda v: value


def _node(e: sp.Basic, index: dict) -> _Node:
    if e.is_Symbol:
        if e not in index:
            raise _Unknown(e)
        i = index[e]
        return lambda v: v[i]
    if e.is_Integer:
        return _const(int(e))  # exact in mixed mpmath arithmetic, like lambdify's int literals
    if e.is_Rational:
        p, q = int(e.p), int(e.q)
        return lambda v: mpmath.mpf(p) / q  # rounded at the working precision of the call
    if e.is_Float:
        mpf = e._mpf_
        return lambda v: mpmath.mpf(mpf)
    if e is sp.pi:
        return lambda v: +mpmath.pi
    if e is sp.E:
        return lambda v: +mpmath.e
    if e is sp.I:
        return lambda v: mpmath.mpc(0, 1)
    if e.is_Add or e.is_Mul:
        parts = [_node(a, index) for a in e.args]
        first, rest = parts[0], parts[1:]
        if e.is_Add:
            def add(v):
                acc = first(v)
                for f in rest:
                    acc = acc + f(v)
                return acc
            return add

        def mul(v):
            acc = first(v)
            for f in rest:
                acc = acc * f(v)
            return acc
        return mul
    if e.is_Pow:
        base, ex = e.args
        b = _node(base, index)
        if ex == sp.S.Half:
            return lambda v: mpmath.sqrt(b(v))
        if ex == -sp.S.Half:
            return lambda v: 1 / mpmath.sqrt(b(v))
        if ex.is_Integer:
            n = int(ex)
            return lambda v: _mp(b(v)) ** n
        x = _node(ex, index)
        return lambda v: _mp(b(v)) ** x(v)
    fn = _FUNCTIONS.get(type(e))
    if fn is not None:
        args = [_node(a, index) for a in e.args]
        return lambda v: fn(*[a(v) for a in args])
    raise _Unknown(type(e).__name__)


def _mp(x):
    """An exact Python int as an mpmath number (``3 ** -1`` must not become a float)."""
    return mpmath.mpf(x) if isinstance(x, int) else x


def mp_function(expr: sp.Expr, symbols: tuple) -> Callable:
    """``expr`` as a function of ``symbols``' values (mpmath numbers), evaluated at the working precision.

    Parameters
    ----------
    expr : sympy.Expr
    symbols : tuple of sympy.Symbol
        The arguments, in order.

    Returns
    -------
    callable
        ``f(*values) -> mpf or mpc``.
    """
    try:
        root = _node(expr, {s: i for i, s in enumerate(symbols)})
    except _Unknown:
        return sp.lambdify(symbols, expr, modules="mpmath")
    return lambda *values: root(list(values))


# -- with a running error bound ------------------------------------------------------------------
class _Unbounded(Exception):
    """A node without an error rule (the caller falls back to comparing precisions)."""


def _bnode(e: sp.Basic, index: dict):
    """A closure ``v -> (value, bound)``: the value at the working precision and a first-order bound on
    its distance to the exact value at the same (exact) inputs, from the rounding ``u = eps`` of each
    operation (forward error analysis, as :meth:`derive.expr_tree.Expr.evaluate_error` does in float64).

    Two precisions agreeing does not prove a value: a term lost at both (``(1e269 + 0.618) - 1e269``
    is exactly 0 at 60 and at 120 digits) gives the same wrong result twice. The bound sees the
    cancellation: it carries the size of the terms that cancelled.
    """
    if e.is_Symbol:
        if e not in index:
            raise _Unbounded(e)
        i = index[e]
        return lambda v: (v[i], abs(v[i]) * mpmath.eps)  # inputs: exact rationals rounded once
    if e.is_Integer:
        n = int(e)
        return lambda v: (mpmath.mpf(n), abs(mpmath.mpf(n)) * mpmath.eps)
    if e.is_Rational:
        p, q = int(e.p), int(e.q)

        def rational(v):
            x = mpmath.mpf(p) / q
            return x, abs(x) * mpmath.eps
        return rational
    if e is sp.pi:
        return lambda v: (+mpmath.pi, mpmath.pi * mpmath.eps)
    if e.is_Add:
        return _badd([_bnode(a, index) for a in e.args])
    if e.is_Mul:
        return _bmul([_bnode(a, index) for a in e.args])
    if e.is_Pow:
        return _bpow(e, index)
    if isinstance(e, (sp.cos, sp.sin)):
        a = _bnode(e.args[0], index)
        fn = mpmath.cos if isinstance(e, sp.cos) else mpmath.sin
        return lambda v: (lambda x, err: (fn(x), err + 2 * mpmath.eps))(*a(v))
    if isinstance(e, sp.acos):
        return _bacos(_bnode(e.args[0], index))
    raise _Unbounded(type(e).__name__)


def _badd(parts: list):
    def add(v):
        acc, err, size = mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
        for f in parts:
            x, ex = f(v)
            acc, err, size = acc + x, err + ex, size + abs(x)
        return acc, err + len(parts) * size * mpmath.eps  # each partial sum rounds by at most u times the sizes
    return add


def _bmul(parts: list):
    def mul(v):
        vals = [f(v) for f in parts]
        acc = mpmath.mpf(1)
        for x, _ in vals:
            acc = acc * x
        if acc == 0:  # a zero factor: its error times the sizes of the others
            err = mpmath.mpf(0)
            for j, (_, ex) in enumerate(vals):
                other = mpmath.mpf(1)
                for k, (y, ey) in enumerate(vals):
                    if k != j:
                        other *= abs(y) + ey
                err += ex * other
            return acc, err
        rel = mpmath.fsum(ex / abs(x) for x, ex in vals)
        return acc, abs(acc) * (rel + len(vals) * mpmath.eps)
    return mul


def _bpow(e: sp.Basic, index: dict):
    base, ex = e.args
    b = _bnode(base, index)
    if not ex.is_Rational:
        raise _Unbounded(e)
    pw = mpmath.mpf(int(ex.p)) / int(ex.q)
    half = ex == sp.S.Half

    def power(v):
        x, err = b(v)
        if x == 0 or err >= abs(x) / 2:  # no relative rule: Hölder for 0 < p <= 1, else unbounded
            if 0 < ex <= 1:
                val = mpmath.sqrt(x) if half else (mpmath.mpf(0) if x == 0 else _mp(x) ** pw)
                return val, (abs(x) + err) ** pw + abs(val) * mpmath.eps
            return (_mp(x) ** pw if x != 0 else mpmath.inf), mpmath.inf
        val = mpmath.sqrt(x) if half else _mp(x) ** pw
        return val, abs(val) * (abs(pw) * err / abs(x) + 2 * mpmath.eps)
    return power


def _bacos(a):
    def acos(v):
        x, err = a(v)
        val = mpmath.acos(x)
        gap = 1 - abs(x)
        if gap > 2 * err:  # |d acos/dx| = 1/sqrt(1 - x²) <= 1/sqrt(gap) on the interval
            return val, err / mpmath.sqrt(gap - err) + 2 * mpmath.eps
        return val, 2 * mpmath.sqrt(2 * (err + max(gap, 0))) + 2 * mpmath.eps  # Hölder at ±1
    return acos


def mp_function_bounded(expr: sp.Expr, symbols: tuple) -> Callable | None:
    """``expr`` as ``f(*values) -> (value, error bound)`` at the working precision, or None where a node
    has no error rule (the caller then compares precisions). See :func:`_bnode`.

    The bound is first order in the unit roundoff (``mpmath.eps``): a value is settled when the bound
    is far below it, and certainly below a floor when value plus bound are.
    """
    try:
        root = _bnode(expr, {s: i for i, s in enumerate(symbols)})
    except _Unbounded:
        return None

    def f(*values):
        val, err = root(list(values))
        if isinstance(val, mpmath.mpc):  # a real quantity: an imaginary part is rounding noise
            return val.real, err + abs(val.imag)
        return val, err
    return f


__all__ = ["mp_function", "mp_function_bounded"]
