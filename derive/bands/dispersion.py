"""The dispersion relation of a periodic scene, symbolically.

Bloch waves u_{c,a} = U_a e^{iqc} (q the phase per cell, in [−π, π]) turn the infinite chain into
K(q) U = ω² M U with the p × p Hermitian K(q) (a spring from mass a to mass b of the cell ``reach`` cells on adds
k at (a, a) and (b, b) and −k e^{iq·reach} at (a, b)); D(q) = M^-1/2 K(q) M^-1/2. Its characteristic polynomial

    det(K(q) − ω² M) = Σ_j c_j(q) (−ω²)^j

has coefficients that are sums of positive terms in the stiffnesses, masses and sin²(zq/2)
(:mod:`.elimination`). Closed-form branches:

* p = 1: ω² = c_0 / c_1;
* p = 2: ω²_+ = (a + d)/2 + sqrt(((a − d)/2)² + |b|²) with a, d the diagonal of D and b its corner, and
  ω²_− = c_0 / (c_2 ω²_+) (no cancellation);
* larger cells when the polynomial factors in ω² into pieces of degree at most 2 (tried up to
  :data:`MAX_FACTOR_CELL` masses).

Without a spring to the ground c_0 carries sin²(q/2): the lowest branch is written ω_0 = sin(q/2)·sqrt(R(q)/…)
with R > 0, so that ω_0(0) = 0 exactly and its group velocity dω/dq needs no division by ω. The complex band
structure has a closed form when the polynomial is linear in cos q (one spring links a cell to the next):
cos q(ω²) = …, and Im q = arccosh|cos q| in a gap.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from .elimination import coefficients
from .model import BandCell

#: Cells of at most this many masses get every coefficient of the characteristic polynomial (2^p determinants).
MAX_POLY_CELL = 4
#: Cells of at most this many masses are tried for a factorisation of the polynomial in ω².
MAX_FACTOR_CELL = 4
#: Largest cell whose det K(q) is formed symbolically (the elimination's expressions grow with p; a cell of 30
#: masses took minutes): past it only the numeric route runs.
MAX_DET_CELL = 8


@dataclass(frozen=True)
class Dispersion:
    """D(q), the characteristic polynomial and the closed-form branches of a unit cell.

    Attributes
    ----------
    cell : BandCell
    q : sympy.Symbol
        The phase per cell (real).
    omega : sympy.Symbol
        The angular frequency (positive): the polynomial is in omega**2.
    """

    cell: BandCell
    q: sp.Symbol
    omega: sp.Symbol

    @property
    def p(self) -> int:
        return self.cell.size

    @property
    def links(self) -> list[tuple[int, int, int, sp.Expr]]:
        """The springs as ``(a, b, reach, k)``."""
        return [(s.a, s.b, s.reach, s.k) for s in self.cell.springs]

    @cached_property
    def K(self) -> sp.Matrix:
        """K(q), p × p Hermitian, with the phases written e^{iq·reach}."""
        return bloch_matrix(self.p, self.links, self.q)

    @cached_property
    def C(self) -> sp.Matrix | None:
        """C(q) of the cell's dashpots (the same form as K), or None."""
        if not self.cell.dampers:
            return None
        return bloch_matrix(self.p, [(d.a, d.b, d.reach, d.k) for d in self.cell.dampers], self.q)

    @cached_property
    def M(self) -> sp.Matrix:
        return sp.diag(*self.cell.masses)

    @cached_property
    def D(self) -> sp.Matrix:
        """M^-1/2 K(q) M^-1/2."""
        r = [1 / sp.sqrt(m) for m in self.cell.masses]
        return sp.Matrix(self.p, self.p, lambda i, j: sp.simplify(self.K[i, j] * r[i] * r[j]))

    @cached_property
    def coefficients(self) -> tuple | None:
        """c_0 … c_p of det(K − ω²M) = Σ c_j (−ω²)^j, sums of positive terms (None past MAX_POLY_CELL)."""
        if self.p > MAX_POLY_CELL:
            return None
        return tuple(_tidy(c) for c in coefficients(self.cell.masses, self.links, self.q))

    @cached_property
    def determinant(self) -> sp.Expr | None:
        """c_0 = det K(q), a sum of positive terms (None past MAX_DET_CELL)."""
        from .elimination import determinant

        if self.coefficients is not None:
            return self.coefficients[0]
        if self.p > MAX_DET_CELL:
            return None
        return _tidy(determinant(self.p, self.links, self.q))

    @cached_property
    def polynomial(self) -> sp.Expr | None:
        """det(K(q) − ω²M) in omega**2 (None past MAX_POLY_CELL)."""
        if self.coefficients is None:
            return None
        return sp.Add(*[c * (-self.omega ** 2) ** j for j, c in enumerate(self.coefficients)])

    @cached_property
    def branches(self) -> tuple | None:
        """Closed-form ω²_j(q), lowest first where ordered (None without one)."""
        return None if self._closed is None else tuple(b for b, _ in self._closed)

    @cached_property
    def frequencies(self) -> tuple | None:
        """Closed-form ω_j(q) for q in [0, π] (even in q), the lowest written sin(q/2)·sqrt(…) without a
        ground spring (None without closed forms)."""
        return None if self._closed is None else tuple(w for _, w in self._closed)

    @cached_property
    def velocities(self) -> tuple | None:
        """dω_j/dq of :attr:`frequencies` for q in [0, π] [cells/s]."""
        if self.frequencies is None:
            return None
        return tuple(sp.diff(w, self.q) for w in self.frequencies)

    @cached_property
    def _closed(self):
        if self.p > MAX_FACTOR_CELL:
            return None
        p, c0 = self.p, self.determinant
        if p == 1:
            m = self.cell.masses[0]
            return ((c0 / m, self._lowest(c0, m)),)
        if p == 2:
            a, d = (sp.factor(self.K[j, j] / self.cell.masses[j]) for j in range(2))
            b2 = _abs2(self.K[0, 1]) / (self.cell.masses[0] * self.cell.masses[1])
            top = (a + d) / 2 + sp.sqrt(((a - d) / 2) ** 2 + b2)
            c2 = self.cell.masses[0] * self.cell.masses[1]
            return ((c0 / (c2 * top), self._lowest(c0, c2 * top)), (top, sp.sqrt(top)))
        if p <= MAX_FACTOR_CELL and self.polynomial is not None:
            return self._factored()
        return None

    def _lowest(self, c0: sp.Expr, rest: sp.Expr) -> sp.Expr:
        """ω of the branch c0/rest: sin(q/2)·sqrt(R/rest) when c0 = sin²(q/2)·R (no ground spring)."""
        if self.cell.grounded:
            return sp.sqrt(c0 / rest)
        R = over_sin2(c0, self.q)
        return sp.sqrt(c0 / rest) if R is None else sp.sin(self.q / 2) * sp.sqrt(R / rest)

    def _factored(self):
        x = sp.Symbol("_lambda", positive=True)
        poly = self.polynomial.subs(self.omega ** 2, x)
        try:
            _, factors = sp.factor_list(sp.expand(poly))  # over every generator (sin(zq/2) too)
        except (sp.PolynomialError, NotImplementedError):
            return None
        degrees = [sp.degree(f, x) for f, _ in factors]
        if any(d > 2 for d in degrees) or sum(d * e for d, (_, e) in zip(degrees, factors)) != self.p or len(factors) < 2:
            return None
        out = []
        for f, mult in factors:
            cs = sp.Poly(f, x).all_coeffs()
            if len(cs) == 2:
                roots = [-cs[1] / cs[0]]
            elif len(cs) == 3:
                A, B, C = cs
                disc = sp.sqrt(B ** 2 - 4 * A * C)
                roots = [2 * C / (-B + disc), (-B + disc) / (2 * A)]
            else:
                continue
            for r in roots:
                r = sp.factor(r)
                out += [(r, sp.sqrt(r))] * int(mult)
        values = self.cell.values  # branches lowest first near q = 0 (the numeric route's continuity order)
        return tuple(sorted(out, key=lambda bw: [complex(sp.N(bw[0].subs(values).subs(self.q, x), 20)).real
                                                 for x in (sp.Rational(1, 1000), sp.Rational(1, 10))]))

    @cached_property
    def cos_q(self) -> sp.Expr | None:
        """cos q as a function of omega**2 when the polynomial is linear in cos q (else None)."""
        if self.polynomial is None:
            return None
        c = sp.Symbol("_c", real=True)
        s = self.polynomial.replace(lambda e: isinstance(e, sp.sin) and e.args[0] == self.q / 2,
                                    lambda e: sp.sqrt((1 - c) / 2))
        s = sp.expand(s)
        if s.has(self.q):
            return None
        try:
            poly = sp.Poly(s, c)
        except sp.PolynomialError:
            return None
        if poly.degree() != 1:
            return None
        a1, a0 = poly.all_coeffs()
        return sp.factor(-a0 / a1)


def bloch_matrix(p: int, links, q: sp.Symbol) -> sp.Matrix:
    """K(q) of springs (or C(q) of dashpots) ``(a, b, reach, k)`` (either end -1 the ground)."""
    K = sp.zeros(p, p)
    for a, b, r, k in links:
        if a < 0 or b < 0:
            c = b if a < 0 else a
            K[c, c] += k
        elif a == b:
            K[a, a] += 4 * k * sp.sin(r * q / 2) ** 2
        else:
            K[a, a] += k
            K[b, b] += k
            K[a, b] += -k * sp.exp(sp.I * q * r)
            K[b, a] += -k * sp.exp(-sp.I * q * r)
    return K


def _abs2(z: sp.Expr) -> sp.Expr:
    """|z|² of Σ −k e^{iqr} written with cosines."""
    out = sp.expand(z * sp.conjugate(z))
    return sp.factor(sp.expand(out.rewrite(sp.cos)))


def _positive(expr: sp.Expr) -> bool:
    """No negative number anywhere in the expression tree (a sum of positive terms when the symbols are)."""
    return not any(isinstance(a, sp.Number) and a < 0 for a in sp.preorder_traversal(expr))


def _tidy(expr: sp.Expr) -> sp.Expr:
    """A short form of a positive nested sum, kept only if it stays free of negative numbers."""
    try:
        short = sp.factor(sp.cancel(expr))
    except (sp.PolynomialError, RecursionError):
        return expr
    return short if _positive(short) else expr


def over_sin2(c0: sp.Expr, q: sp.Symbol) -> sp.Expr | None:
    """R with c0 = sin²(q/2)·R, each sin²(zq/2) of a term written sin²(q/2)·U_z(q)² (U_z a sum of cosines:
    positive near q = 0); None when some term has no squared sine."""
    gens = sorted({a for a in c0.atoms(sp.sin) if (a.args[0] / q).is_Rational}, key=sp.default_sort_key)
    if not gens:
        return None
    poly = sp.Poly(sp.expand(c0), *gens)
    out = []
    for exps, coeff in poly.terms():
        j = next((j for j, e in enumerate(exps) if e >= 2), None)
        if j is None:
            return None
        z = sp.Rational(gens[j].args[0] / q) * 2
        if not z.is_integer:
            return None
        U = sp.Add(*[sp.cos((int(z) - 1 - 2 * k) * q / 2) for k in range(int(z))])
        e = list(exps)
        e[j] -= 2
        out.append(coeff * U ** 2 * sp.Mul(*[g ** n for g, n in zip(gens, e)]))
    return sp.factor(sp.Add(*out)) if all(_positive(t) for t in out) else sp.Add(*out)


def dispersion(cell: BandCell) -> Dispersion:
    return Dispersion(cell, sp.Symbol("q", real=True), sp.Symbol("omega", positive=True))


__all__ = ["MAX_FACTOR_CELL", "MAX_POLY_CELL", "Dispersion", "bloch_matrix", "dispersion", "over_sin2"]
