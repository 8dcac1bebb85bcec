"""Cancellation-free forms of a spring law: force V'(d) and energy V(d) − V(0) near d = 0.

A potential such as Toda's ``a/b*exp(-b*d) + a*d`` has the force ``a − a*exp(−b d)``: two terms
of size ``a`` whose difference is ``a·b·d``, so in float64 the force at ``d = 1e-9`` keeps only
seven digits. The remedy is structural: a function that vanishes at d = 0 is written as a
*difference* ``f(d) − f(0)``, and every difference of an elementary function has a form without
subtraction of nearly equal numbers::

    Δ exp(u)   = exp(u0) · expm1(Δu)
    Δ log(u)   = log1p(Δu / u0)
    Δ u**p     = u0**p · expm1(p · log1p(Δu / u0))    (Δu (u + u0) / ... for p = 2, 1/2)
    Δ sin(u)   = 2 cos(u0 + Δu/2) sin(Δu/2)           (cos, sinh, cosh, tanh alike)
    Δ (a b)    = Δa · b + a0 · Δb,   Δ (a + b) = Δa + Δb

with ``u0 = u(0)`` and ``Δu = u(d) − u0`` formed the same way, recursively (:func:`delta`). A
force with V'(0) = 0 is printed as ``Δ V'``; with V'(0) ≠ 0 as ``V'(0) + Δ V'``. The energy
``V(d) − V(0)`` vanishes to second order when V'(0) = 0, so it needs the second difference
``Δ₂ f = f(d) − f(0) − f'(0) d`` (:func:`delta2`: ``Δ₂ exp(u) = exp(u0) (expm1mx(Δu) + Δ₂u)``
with ``expm1mx(z) = expm1(z) − z``, polynomials as they are, products by the product rule), after
SymPy's ``factor`` has had the chance to turn it into a product (Morse and Lennard-Jones energies
factor into squares of differences).

Every rewrite is an identity: the result equals the input as a function of d (the tests check
it symbolically at random points in 60-digit arithmetic). What is *not* promised: terms of
opposite sign in the first-order part of the force (a non-convex sum that nearly cancels in its
slope) keep their cancellation, as any formula would.
"""

from __future__ import annotations

import sympy as sp
from sympy.codegen.cfunctions import expm1, log1p

#: Integer powers up to this size use the factor (u - u0) * sum(u**k u0**(p-1-k)); larger ones and
#: fractional ones use expm1(p*log1p(du/u0)) (valid where u/u0 > 0, the only place they are real).
MAX_FACTORED_POWER = 4


class _MinusIdentity(sp.Function):
    """``f(z) − z`` for an mpmath function ``f`` with ``f(0) = 0`` and ``f'(0) = 1`` (second order
    at 0): zero at 0 by SymPy's automatic simplification, evaluated in mpmath with guard digits."""

    #: The mpmath function f (a name, so mpmath is imported only when evaluating).
    _mpmath_f = ""

    @classmethod
    def eval(cls, z):  # SymPy's Function hook for automatic simplification; no text is evaluated
        if z.is_zero:
            return sp.Integer(0)

    def _eval_evalf(self, prec):
        import mpmath

        z = self.args[0].evalf(prec)
        if not z.is_Number:
            return None
        with mpmath.workprec(prec + 20):
            v = getattr(mpmath, self._mpmath_f)(mpmath.mpf(z._mpf_)) - mpmath.mpf(z._mpf_)
        return sp.Float(v, precision=prec)


class expm1mx(_MinusIdentity):
    """``expm1mx(z) = exp(z) − 1 − z`` (second order at 0), evaluated without cancellation.

    Generated modules print it as a private helper (``_expm1mx``: a series for |z| < 1/2,
    ``expm1(z) − z`` beyond); SymPy differentiates it as ``expm1(z)`` and evaluates it with mpmath.
    """

    nargs = 1
    _mpmath_f = "expm1"

    def fdiff(self, argindex=1):
        return expm1(self.args[0])

    def _eval_rewrite_as_exp(self, z, **kwargs):
        return sp.exp(z) - 1 - z


class log1pmx(_MinusIdentity):
    """``log1pmx(z) = log(1 + z) − z`` (second order at 0), evaluated without cancellation
    (generated modules: the private helper ``_log1pmx``)."""

    nargs = 1
    _mpmath_f = "log1p"

    def fdiff(self, argindex=1):
        z = self.args[0]
        return -z / (1 + z)

    def _eval_rewrite_as_log(self, z, **kwargs):
        return sp.log(1 + z) - z


#: The second-order helpers and the private names generated code calls them by.
HELPER_NAMES = {"expm1mx": "_expm1mx", "log1pmx": "_log1pmx"}


def plain(expr: sp.Expr) -> sp.Expr:
    """``expr`` with expm1, log1p, expm1mx and log1pmx written back in exp and log (for checks)."""
    expr = expr.replace(log1pmx, lambda z: sp.log(1 + z) - z)
    return expr.replace(expm1mx, lambda z: sp.exp(z) - 1 - z).replace(
        expm1, lambda z: sp.exp(z) - 1).replace(log1p, lambda z: sp.log(1 + z))


def _at0(expr: sp.Expr, d: sp.Symbol) -> sp.Expr:
    """``expr`` at d = 0 (a limit where direct substitution is undefined)."""
    v = expr.subs(d, 0)
    if v.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        v = sp.limit(expr, d, 0)
    return v


def _is_zero(expr: sp.Expr) -> bool:
    return expr == 0 or sp.simplify(expr) == 0


def delta(f: sp.Expr, d: sp.Symbol) -> sp.Expr:
    """``f(d) − f(0)`` in a form without cancellation at small d (see the module docstring).

    Parameters
    ----------
    f : sympy.Expr
        A function of ``d`` (and of parameters) finite at d = 0.
    d : sympy.Symbol

    Returns
    -------
    sympy.Expr
        Equal to ``f − f.subs(d, 0)`` identically in d.
    """
    if not f.has(d):
        return sp.Integer(0)
    if f == d:
        return f
    if f.is_Add:
        return sp.Add(*(delta(t, d) for t in f.args))
    if f.is_Mul:
        const = sp.Mul(*(a for a in f.args if not a.has(d)))
        parts = [a for a in f.args if a.has(d)]
        if len(parts) == 1:
            return const * delta(parts[0], d)
        a, b = parts[0], sp.Mul(*parts[1:])
        return const * (delta(a, d) * b + _at0(a, d) * delta(b, d))
    if f.is_Pow:
        base, p = f.args
        if p.has(d):  # u**v = exp(v log u)
            return delta(sp.exp(p * sp.log(base)), d)
        u0 = _at0(base, d)
        du = delta(base, d)
        if _is_zero(u0):  # f(0) = 0 for p > 0 (a negative power is not finite at 0: never asked)
            return du**p
        if p.is_Integer and 0 < abs(p) <= MAX_FACTORED_POWER:
            q = abs(int(p))
            s = sp.Add(*(base**k * u0 ** (q - 1 - k) for k in range(q)))
            diff = du * s  # base**q - u0**q
            return diff if p > 0 else -diff / (base**q * u0**q)
        if p == sp.Rational(1, 2):
            return du / (sp.sqrt(base) + sp.sqrt(u0))
        return u0**p * expm1(p * log1p(du / u0))
    if isinstance(f, sp.exp):
        u = f.args[0]
        return sp.exp(_at0(u, d)) * expm1(delta(u, d))
    if isinstance(f, sp.log):
        u = f.args[0]
        return log1p(delta(u, d) / _at0(u, d))
    if isinstance(f, expm1):  # expm1(u) - expm1(u0) = exp(u0) expm1(du)
        u = f.args[0]
        return sp.exp(_at0(u, d)) * expm1(delta(u, d))
    if isinstance(f, log1p):
        u = f.args[0]
        return log1p(delta(u, d) / (1 + _at0(u, d)))
    if isinstance(f, (sp.sin, sp.cos, sp.sinh, sp.cosh)):
        u = f.args[0]
        u0, h = _at0(u, d), delta(u, d) / 2
        mid = u0 + h
        if isinstance(f, sp.sin):
            return 2 * sp.cos(mid) * sp.sin(h)
        if isinstance(f, sp.cos):
            return -2 * sp.sin(mid) * sp.sin(h)
        if isinstance(f, sp.sinh):
            return 2 * sp.cosh(mid) * sp.sinh(h)
        return 2 * sp.sinh(mid) * sp.sinh(h)
    if isinstance(f, sp.tanh):
        u = f.args[0]
        u0 = _at0(u, d)
        return sp.sinh(delta(u, d)) / (sp.cosh(u) * sp.cosh(u0))
    return f - _at0(f, d)  # anything else (Abs, sign, ...): as it is


def delta2(f: sp.Expr, d: sp.Symbol, fallbacks: list | None = None) -> sp.Expr:
    """``f(d) − f(0) − f'(0)·d`` in a form without cancellation at small d where it can.

    Exact forms for sums, products, powers (``Δ₂ u**p = u0**p [expm1mx(p log1p z) + p log1pmx(z)
    + p Δ₂u/u0]`` with ``z = Δu/u0``), exp, log, cosh and cos of functions vanishing at 0, and
    polynomials in d; anything else falls back to ``Δf − f'(0) d`` (which cancels to first order)
    and is appended to ``fallbacks`` if given.
    """
    if not f.has(d) or f == d:
        return sp.Integer(0)
    if f.is_Add:
        return sp.Add(*(delta2(t, d, fallbacks) for t in f.args))
    if f.is_Mul:
        const = sp.Mul(*(a for a in f.args if not a.has(d)))
        parts = [a for a in f.args if a.has(d)]
        if len(parts) == 1:
            return const * delta2(parts[0], d, fallbacks)
        a, b = parts[0], sp.Mul(*parts[1:])
        a0, a1 = _at0(a, d), _at0(sp.diff(a, d), d)
        return const * (delta2(a, d, fallbacks) * b + a1 * d * delta(b, d) + a0 * delta2(b, d, fallbacks))
    if f.is_Pow and not f.exp.has(d):
        base, p = f.args
        u0 = _at0(base, d)
        if _is_zero(u0):
            if p.is_number and p >= 2:  # f(0) = f'(0) = 0
                return delta(base, d) ** p
        elif p.is_Integer and 2 <= p <= MAX_FACTORED_POWER:  # u² = u0² + 2 u0 Δu + Δu², ...
            du = delta(base, d)
            return sp.Add(*(sp.binomial(p, j) * u0 ** (p - j) * du**j for j in range(2, int(p) + 1))) \
                + p * u0 ** (p - 1) * delta2(base, d, fallbacks)
        else:
            z = delta(base, d) / u0
            return u0**p * (expm1mx(p * log1p(z)) + p * log1pmx(z) + p * delta2(base, d, fallbacks) / u0)
    if isinstance(f, sp.exp):
        u = f.args[0]
        return sp.exp(_at0(u, d)) * (expm1mx(delta(u, d)) + delta2(u, d, fallbacks))
    if isinstance(f, (sp.log, log1p)):  # log(u) = log(u0) + log1p(z), z = du/u0 (u0 -> 1 + u0 for log1p)
        u = f.args[0]
        u0 = _at0(u, d) + (1 if isinstance(f, log1p) else 0)
        return log1pmx(delta(u, d) / u0) + delta2(u, d, fallbacks) / u0
    if isinstance(f, (sp.cosh, sp.cos)) and _is_zero(_at0(f.args[0], d)):  # cosh u - 1 = 2 sinh²(u/2)
        h = delta(f.args[0], d) / 2
        return 2 * sp.sinh(h) ** 2 if isinstance(f, sp.cosh) else -2 * sp.sin(h) ** 2
    if fallbacks is not None:
        fallbacks.append(f)
    return delta(f, d) - _at0(sp.diff(f, d), d) * d


def stable_force(force: sp.Expr, d: sp.Symbol) -> sp.Expr:
    """The force law V'(d) for generated code: ``ΔV'`` (plus ``V'(0)`` when that is not 0)."""
    f0 = _at0(force, d)
    return delta(force, d) if _is_zero(f0) else f0 + delta(force, d)


def stable_energy(energy: sp.Expr, d: sp.Symbol) -> sp.Expr:
    """``V(d) − V(0)`` for generated code: second differences when V'(0) = 0, else first.

    Term by term (each additive term of V loses its own linear part, so linear parts that cancel
    between terms, as in Toda's ``a/b exp(-b d) + a d``, never meet); a term whose second difference
    has no exact form is tried through SymPy's ``factor`` too (a Morse or Lennard-Jones energy becomes
    a square of a function vanishing at 0), kept if it is no longer than eight times the term.
    """
    slope = _at0(sp.diff(energy, d), d)
    if not _is_zero(slope):
        return delta(energy, d)
    out = []
    for term in sp.Add.make_args(energy):
        missed: list = []
        form = delta2(term, d, missed)
        if missed:
            shifted = term - _at0(term, d)
            try:
                factored = sp.factor(shifted, d)
            except (sp.PolynomialError, NotImplementedError):  # pragma: no cover - SymPy gives up
                factored = shifted
            if factored != shifted and sp.count_ops(factored) <= 8 * max(sp.count_ops(shifted), 1):
                again: list = []
                alt = delta2(factored, d, again)
                if not again:
                    form = alt
        out.append(form)
    return sp.Add(*out)


__all__ = ["expm1", "log1p", "expm1mx", "log1pmx", "HELPER_NAMES", "delta", "delta2", "stable_force", "stable_energy", "plain"]
