"""Deterministic work caps of the symbolic algebra (no clock anywhere).

Whether a scene gets a closed form must not depend on how busy the machine is: ``springchain
derive`` has to write the same module on any machine, under any load, so that ``derive --check``
is stable. Every expensive symbolic step is therefore gated by a size measured *before* the work,
from the expressions themselves:

* :func:`det_terms_bound` bounds the number of monomials of ``det(A)`` for a polynomial matrix
  ``A`` (the product over its rows of the monomials in each row, and the count of monomials of
  its total degree in its symbols, whichever is smaller); the expansion and factorisation of a
  determinant cost about its number of terms times the number of its symbols.
* :func:`ops` is SymPy's operation count, the size of an expression before a simplification.

Past a cap the caller raises :class:`WorkCapExceeded` and falls back to numeric values (with a
note), exactly as it does for a factor of too high a degree.
"""

from __future__ import annotations

import contextlib
import os
from math import comb

import sympy as sp

from .caps import CAPS
from .expr import as_sympy

#: Largest bound on the terms of a characteristic polynomial that is expanded and factored
#: (bundled scenes: at most 36; a general 4-mass chain with 9 distinct symbols: 400, ~1.5 s;
#: a general 5-mass chain, 2000, would take ~4 s and has no readable closed form anyway).
MAX_DET_TERMS = CAPS.det_terms


class WorkCapExceeded(Exception):
    """The symbolic work would exceed one of the deterministic caps (a size, never a time)."""


def monomials(expr: sp.Expr) -> int:
    """Number of terms of ``expr`` as written (an expanded polynomial: its monomials)."""
    return len(sp.Add.make_args(expr)) if expr != 0 else 0


def det_terms_bound(A: sp.Matrix) -> int:
    """An upper bound on the number of monomials of ``det(A)`` for a square matrix of expanded
    polynomials (exact enough to gate the expansion: 36 for a bundled 3-mass block, 10 000 for a
    6-mass chain of 14 distinct symbols).

    Parameters
    ----------
    A : sympy.Matrix, shape (n, n)

    Returns
    -------
    int
        ``min(∏_rows Σ_entries terms, C(s + d, d))`` with ``s`` the number of generators (symbols,
        and powers such as ``1/m`` or ``√m``) and ``d`` the sum over the rows of the largest total
        degree of an entry.
    """
    product, degree, gens = 1, 0, set()
    for i in range(A.rows):
        row = [sp.Poly(e) for e in A.row(i) if e != 0 and e.free_symbols]  # generators: symbols, 1/m, √m, ...
        product *= sum(monomials(e) for e in A.row(i) if e != 0)
        degree += max((p.total_degree() for p in row), default=0)
        gens.update(g for p in row for g in p.gens)
    return min(product, comb(len(gens) + degree, degree))


def ops(expr) -> int:
    """SymPy's operation count of ``expr`` (a size measured before simplifying it)."""
    return int(sp.count_ops(expr))


def radical_depth(expr) -> int:
    """Deepest nesting of radicals (powers with a non-integer rational exponent) whose base has symbols:
    ``sqrt(a + sqrt(b))`` has 2, ``sqrt(a + sqrt(b + sqrt(c)))`` 3, ``sqrt(2)*x`` 0 (a size measured before
    simplifying)."""
    if not getattr(expr, "args", ()):
        return 0
    inner = max(radical_depth(a) for a in expr.args)
    if (isinstance(expr, sp.Pow) and expr.exp.is_Rational and not expr.exp.is_Integer
            and expr.base.free_symbols):
        return inner + 1
    return inner


#: Most decimal digits (numerator and denominator) of an exact number in the matrices whose
#: characteristic polynomial is factored: literals such as ``2e-70`` are exact rationals, and their
#: products in a determinant run to hundreds of digits, where factoring takes seconds and the closed
#: form is a wall of digits nobody reads (the numeric route is exact to float64 either way).
MAX_NUMBER_DIGITS = CAPS.number_digits


class NumbersTooLong(WorkCapExceeded):
    """An exact number of the symbolic problem is longer than :data:`MAX_NUMBER_DIGITS` digits."""


def number_digits(exprs) -> int:
    """The most decimal digits (numerator plus denominator) of a rational number in ``exprs``."""
    out = 0
    for e in exprs:
        for r in as_sympy(e).atoms(sp.Rational):
            out = max(out, len(str(abs(r.p))) + len(str(r.q)))
    return out


class SymbolicNumbersFailed(WorkCapExceeded):
    """SymPy's own arithmetic on the scene's numbers failed (a fallback, like a work cap).

    SymPy evaluates ``sqrt`` of a large integer at once, through ``factorint(limit=2**15)``,
    which raises on some inputs: SymPy 1.14 caches a composite "prime factor" and raises
    ``ValueError: ... is not a prime factor of ...`` (sympy/sympy#28621: the characteristic
    polynomial of two masses joined by ``k = "2e-70"`` with a unit wall spring), and with gmpy2 on
    Python < 3.13 ``math.log`` of an ``mpz`` past 1e308 raises ``OverflowError`` (a potential
    ``1e200*d**2``; Python's gh-120950). Exact numbers of tens to hundreds of digits come from
    float literals such as ``2e-70`` (kept exact) and their products in determinants.
    """


def _raised_in_sympy(exc: BaseException) -> bool:
    """Whether the innermost frame of ``exc``'s traceback is SymPy's (not springchain's own check)."""
    tb = exc.__traceback__
    if tb is None:
        return False
    while tb.tb_next is not None:
        tb = tb.tb_next
    return os.sep + "sympy" + os.sep in tb.tb_frame.f_code.co_filename


@contextlib.contextmanager
def sympy_numbers():
    """Turn SymPy's internal arithmetic failures inside the block into :class:`SymbolicNumbersFailed`.

    Only a ``ValueError`` or ``OverflowError`` raised from SymPy's own code is converted (the caller then
    falls back to numeric values, as past a work cap); anything raised elsewhere propagates unchanged.
    """
    try:
        yield
    except (ValueError, OverflowError) as exc:
        if not _raised_in_sympy(exc):
            raise
        raise SymbolicNumbersFailed(f"SymPy: {type(exc).__name__}: {str(exc)[:80]}") from exc


def check(size: int, cap: int) -> None:
    """Raise :class:`WorkCapExceeded` when ``size`` is over ``cap``."""
    if size > cap:
        raise WorkCapExceeded(f"{size} > {cap}")


__all__ = ["WorkCapExceeded", "NumbersTooLong", "MAX_NUMBER_DIGITS", "number_digits", "SymbolicNumbersFailed", "sympy_numbers", "MAX_DET_TERMS", "det_terms_bound", "monomials", "ops", "radical_depth", "check"]
