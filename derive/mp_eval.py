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


__all__ = ["mp_function"]
