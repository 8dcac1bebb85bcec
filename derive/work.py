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

from math import comb

import sympy as sp

#: Largest bound on the terms of a characteristic polynomial that is expanded and factored
#: (bundled scenes: at most 36; a general 4-mass chain with 9 distinct symbols: 400, ~1.5 s;
#: a general 5-mass chain, 2000, would take ~4 s and has no readable closed form anyway).
MAX_DET_TERMS = 1000


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


def check(size: int, cap: int) -> None:
    """Raise :class:`WorkCapExceeded` when ``size`` is over ``cap``."""
    if size > cap:
        raise WorkCapExceeded(f"{size} > {cap}")


__all__ = ["WorkCapExceeded", "MAX_DET_TERMS", "det_terms_bound", "monomials", "ops", "check"]
