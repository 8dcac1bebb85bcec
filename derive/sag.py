"""The static sag under gravity, ``x_eq = K⁻¹ M g``: a closed form within the caps, exact values always.

The closed form is found by Gaussian elimination in the field of rational functions of the
scene's symbols (SymPy's sparse polynomials, a gcd per operation), with a deterministic cap: the
elimination stops at the first entry with more than :attr:`Caps.sag_terms` monomials (numerator
plus denominator), and scenes of more than :attr:`Caps.sag_masses` masses or with exact numbers
longer than :attr:`Caps.number_digits` digits are not tried. Expanding ``K.LUsolve(M g)`` and
``cancel``-ing it instead ran past 300 s on six hung masses with named parameters (its nested
fractions have ~800 operations per entry before cancelling); the elimination gives the same sag
in a few hundredths of a second.

The values are always an exact rational solve at the scene's parameter values (float parameters
are exact binary fractions), each correctly rounded to float64 (:func:`accurate.value`): within the
caps they are the closed form's values, past them they stand alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from .accurate import MAX_DPS, NotAccurate, exact_values, mp_value, value
from .caps import CAPS
from .model import Model
from .model_cache import cached_on
from .printing import sstr
from .work import NumbersTooLong, SymbolicNumbersFailed, WorkCapExceeded, number_digits, sympy_numbers


@dataclass(frozen=True)
class Sag:
    """The static equilibrium of a linear scene under gravity.

    Attributes
    ----------
    closed : tuple of sympy.Expr, shape (n,), or None
        ``K⁻¹ M g`` in the scene's parameters (factored), None past a cap.
    exact : tuple of sympy.Rational, shape (n,), or None
        The exact sag at the scene's parameter values (None where an entry of K or M g is irrational:
        ``values`` are then settled in mpmath).
    values : tuple of float, shape (n,)
        ``exact`` correctly rounded.
    why : str
        Empty for a closed form, else the cap that sent the sag to the exact values.
    """

    closed: tuple | None
    exact: tuple
    values: tuple
    why: str = ""


def _size(element) -> int:
    """Monomials of a field element (numerator plus denominator; 1 for a number)."""
    numer = getattr(element, "numer", None)
    if numer is None:
        return 1
    return len(numer) + len(element.denom)


def capped_solve(A: sp.Matrix, b: sp.Matrix, max_terms: int) -> list[sp.Expr]:
    """``A⁻¹ b`` by Gaussian elimination over the rational functions of the entries' symbols.

    Parameters
    ----------
    A : sympy.Matrix, shape (n, n)
        Nonsingular, entries polynomial in their symbols (and in powers such as ``√m``).
    b : sympy.Matrix, shape (n, 1)
    max_terms : int
        Most monomials (numerator plus denominator) any entry may reach during the elimination.

    Returns
    -------
    list of sympy.Expr, length n
        Each a cancelled fraction of polynomials (not factored).

    Raises
    ------
    WorkCapExceeded
        At the first entry past ``max_terms``, or when the entries are not polynomial over a field
        SymPy's sparse polynomials handle (no symbolic elimination is attempted then).
    """
    n = A.rows
    dm = DomainMatrix.from_Matrix(A.row_join(b))
    dom = dm.domain
    if not (dom.is_ZZ or dom.is_QQ or dom.is_PolynomialRing or dom.is_FractionField):
        raise WorkCapExceeded(f"entries over {dom}: no sparse-polynomial elimination")
    dm = dm.to_field()
    dom = dm.domain
    rows = dm.to_list()

    def checked(e):
        if _size(e) > max_terms:
            raise WorkCapExceeded(f"an entry of more than {max_terms} terms")
        return e

    for c in range(n):
        p = next((r for r in range(c, n) if rows[r][c]), None)
        if p is None:
            raise WorkCapExceeded("singular stiffness matrix")
        rows[c], rows[p] = rows[p], rows[c]
        inv = dom.quo(dom.one, rows[c][c])
        rows[c] = [checked(e * inv) if e else e for e in rows[c]]
        for r in range(c + 1, n):
            f = rows[r][c]
            if f:
                rows[r] = [checked(x - f * y) if y else x for x, y in zip(rows[r], rows[c])]
    x = [dom.zero] * n
    for i in reversed(range(n)):
        acc = rows[i][n]
        for j in range(i + 1, n):
            if rows[i][j]:
                acc = checked(acc - rows[i][j] * x[j])
        x[i] = acc
    return [dom.to_sympy(e) for e in x]


def exact_solve(A: sp.Matrix, b: sp.Matrix) -> list[sp.Rational] | None:
    """``A⁻¹ b`` for a matrix of exact rationals (SymPy's exact rational arithmetic, no rounding); None when
    an entry is not rational (``pi``, ``sqrt(2)`` in a scene's expressions)."""
    if not all(e.is_Rational for e in (*A, *b)):
        return None
    dm = DomainMatrix.from_Matrix(A).convert_to(sp.QQ)
    rhs = DomainMatrix.from_Matrix(b).convert_to(sp.QQ)
    return list(dm.lu_solve(rhs).to_Matrix())


def settled_solve(A: sp.Matrix, b: sp.Matrix) -> list[float]:
    """``A⁻¹ b`` for a matrix of exact (irrational) numbers: mpmath's elimination at 30, 60, … digits until two
    precisions agree to 1e-18 per entry, then correctly rounded.

    Raises
    ------
    NotAccurate
        If no two precisions up to :data:`accurate.MAX_DPS` digits agree.
    """
    n = A.rows
    prev, dps = None, 30
    while dps <= MAX_DPS:
        with mpmath.workdps(dps):
            Am = mpmath.matrix([[mp_value(A[i, j], dps) for j in range(n)] for i in range(n)])
            x = mpmath.lu_solve(Am, mpmath.matrix([mp_value(e, dps) for e in b]))
            if prev is not None and all(abs(x[i] - prev[i]) <= mpmath.mpf(10) ** -18 * abs(x[i]) for i in range(n)):
                return [float(x[i]) for i in range(n)]
            prev = x
        dps *= 2
    raise NotAccurate(f"the static sag did not settle within {MAX_DPS} digits")


def _closed(model: Model, rhs: sp.Matrix) -> tuple[tuple | None, str]:
    """The factored closed form, or (None, the cap it ran past)."""
    n = model.scene.n
    if n > CAPS.sag_masses:
        return None, f"more than {CAPS.sag_masses} masses"
    if number_digits(list(model.K) + list(rhs)) > CAPS.number_digits:
        return None, f"exact numbers of more than {CAPS.number_digits} digits"
    try:
        with sympy_numbers():
            sol = capped_solve(model.K, rhs, CAPS.sag_terms)
    except (WorkCapExceeded, NumbersTooLong, SymbolicNumbersFailed) as exc:
        return None, f"symbolic elimination past its cap ({exc})"
    longest = max(len(sstr(e)) for e in sol)
    if longest > CAPS.sag_chars:
        return None, f"its longest entry has {longest} characters, past {CAPS.sag_chars}"
    return tuple(sp.factor(e) for e in sol), ""


def static_sag(model: Model) -> Sag | None:
    """``x_eq = K⁻¹ M g`` of a scene with gravity, no free piece and no spring potential (else None).

    Cached on the model (the text report, its notes and ``--json`` share one computation).
    """
    if model.g is None or model.free_components or model.equilibrium is not None:
        return None
    return cached_on(model, "_static_sag", None, lambda: _static_sag(model))


def _static_sag(model: Model) -> Sag:
    rhs = sp.Matrix(model.gravity_force)
    closed, why = _closed(model, rhs)
    subs = exact_values(model.params, model.scene.parameters)
    K, F = model.K.xreplace(subs), rhs.xreplace(subs)  # symbols -> exact rationals
    exact = exact_solve(K, F)
    values = tuple(value(e, {}) for e in exact) if exact is not None else tuple(settled_solve(K, F))
    return Sag(closed, None if exact is None else tuple(exact), values, why)


def sag_note(sag: Sag) -> str:
    """The report's gravity note: closed forms with their values beside, or the values alone."""
    if sag.closed is not None:
        return ("gravity: static equilibrium (sag) x_eq = K^-1 M g = (" + ", ".join(sstr(e) for e in sag.closed)
                + "); modes are about x_eq (at the scene's values: ("
                + ", ".join(f"{v:.10g}" for v in sag.values) + "))")
    return ("gravity: static equilibrium (sag) x_eq = K^-1 M g = (" + ", ".join(repr(v) for v in sag.values)
            + "); modes are about x_eq (values at the scene's parameters from "
            + ("an exact rational solve" if sag.exact is not None else "mpmath, two precisions agreeing")
            + f"; no closed form: {sag.why})")


__all__ = ["Sag", "capped_solve", "exact_solve", "settled_solve", "static_sag", "sag_note"]
