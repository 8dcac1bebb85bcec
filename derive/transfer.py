"""The transfer function ``H(s) = X_out(s) / F_in(s)`` of a small linear scene, in closed form.

``H(s) = adj(M s² + C s + K)[out, in] / det(M s² + C s + K)``: a cofactor over the determinant,
both polynomials in s with the scene's parameters as symbols, cancelled to lowest terms.
Offered for ``[masses]`` scenes of at most :data:`MAX_MASSES` masses (the determinant of a larger
symbolic matrix is long and says little); cubic springs enter by their linear part.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .caps import CAPS
from .printing import latex, sstr
from .model import Model
from .work import MAX_DET_TERMS, WorkCapExceeded, check, det_terms_bound

#: Largest scene whose transfer function is derived.
MAX_MASSES = CAPS.transfer_masses


@dataclass(frozen=True)
class TransferFunction:
    """``H(s) = numerator / denominator``, polynomials in ``s`` (SymPy, cancelled).

    Attributes
    ----------
    s : sympy.Symbol
    numerator, denominator : sympy.Expr
    input, output : str
        Mass names.
    values : dict of sympy.Symbol to float
        The scene's parameter values (for :meth:`at_values` and :meth:`evaluate`).
    """

    s: sp.Symbol
    numerator: sp.Expr
    denominator: sp.Expr
    input: str
    output: str
    values: dict

    @property
    def expr(self) -> sp.Expr:
        return self.numerator / self.denominator

    def _exact_values(self) -> dict:
        """The parameter values as exact rationals (a float is one): no 15-digit SymPy Float enters."""
        from fractions import Fraction

        return {k: sp.Rational(Fraction(float(v))) for k, v in self.values.items()}

    def at_values(self, digits: int | None = None) -> tuple[str, str]:
        """Numerator and denominator at the scene's values in descending powers of s, the denominator's
        leading coefficient 1: each coefficient computed exactly (rational parameter values) and
        shown as the shortest decimal that reads back as its float64 value (or to ``digits``)."""
        exact = self._exact_values()
        num = sp.Poly(self.numerator.subs(exact), self.s)
        den = sp.Poly(self.denominator.subs(exact), self.s)
        lead = den.LC()
        if digits is None:
            fmt = lambda c: repr(float(sp.N(c / lead, 30)))  # noqa: E731
        else:
            fmt = lambda c: f"{float(sp.N(c / lead, 30)):.{digits}g}"  # noqa: E731
        return _descending(num, fmt, "s"), _descending(den, fmt, "s")

    def text(self) -> str:
        """Two lines: the symbolic ratio, and the ratio at the scene's values."""
        lhs = f"H(s) = X_{self.output}(s)/F_{self.input}(s)"
        n, d = self.at_values()
        sym = lambda e: _descending(sp.Poly(e, self.s), _coefficient(sstr), "s")  # noqa: E731
        return (f"{lhs} = ({sym(self.numerator)}) / ({sym(self.denominator)})\n"
                f"{' ' * (len(lhs) + 1)}= ({n}) / ({d})   (at the scene's values)\n")

    def latex(self) -> str:
        """``H(s) = \\frac{...}{...}`` (amsmath), polynomials in descending powers of s."""
        lhs = (r"H(s) = \frac{X_{\mathrm{" + self.output.replace("_", r"\_") + r"}}(s)}{F_{\mathrm{"
               + self.input.replace("_", r"\_") + r"}}(s)}")
        tex = lambda e: _descending(sp.Poly(e, self.s), _coefficient(latex, r"\left(", r"\right)"), "s",  # noqa: E731
                                    power=lambda k: f"s^{{{k}}}", times=" ")
        return ("\\begin{align*}\n" + lhs + " &= \\frac{" + tex(self.numerator) + "}{"
                + tex(self.denominator) + "}\n\\end{align*}\n")

    def as_json(self) -> dict:
        n, d = self.at_values()
        return {"numerator": sp.sstr(self.numerator), "denominator": sp.sstr(self.denominator),
                "variable": "s", "latex": self.latex(), "numerator_value": n, "denominator_value": d}

    def evaluate(self, s_values):
        """H at complex ``s`` values (the scene's parameters substituted), via mpmath at 30 digits.

        Returns a list of Python complex numbers (the numeric side never imports SymPy; the
        caller turns it into an array).
        """
        exact = self._exact_values()
        num = sp.Poly(self.numerator.subs(exact), self.s)
        den = sp.Poly(self.denominator.subs(exact), self.s)
        import mpmath

        with mpmath.workdps(30):
            ncm = [mpmath.mpf(c.p) / c.q for c in num.all_coeffs()]
            dcm = [mpmath.mpf(c.p) / c.q for c in den.all_coeffs()]
            return [complex(mpmath.polyval(ncm, mpmath.mpc(z)) / mpmath.polyval(dcm, mpmath.mpc(z)))
                    for z in s_values]


def _coefficient(printer, left: str = "(", right: str = ")"):
    """A printer of a polynomial coefficient: a sum is parenthesised."""
    return lambda c: f"{left}{printer(c)}{right}" if isinstance(c, sp.Add) else printer(c)


def _descending(poly: sp.Poly, coefficient, var: str, power=None, times: str = "*") -> str:
    """``c_n*s**n + ... + c_0`` in descending powers (SymPy's printers order terms canonically)."""
    power = power or (lambda k: f"{var}**{k}")
    parts = []
    for (k,), c in poly.terms():
        neg = bool(c.could_extract_minus_sign()) if isinstance(c, sp.Expr) else c < 0
        text = coefficient(-c if neg else c)
        if k:
            mono = var if k == 1 else power(k)
            text = mono if text in ("1", "1.0") else f"{text}{times}{mono}"
        parts.append(("- " if neg else "+ ") + text)
    out = " ".join(parts) or "0"
    return out[2:] if out.startswith("+ ") else "-" + out[2:]


def transfer_function(model: Model, input: int, output: int) -> TransferFunction | None:
    """``H(s)`` from input mass ``input`` to output mass ``output`` (indices), or None when the
    scene is too large (more than :data:`MAX_MASSES` masses) or the determinant is past the work
    cap (:data:`work.MAX_DET_TERMS` terms, bounded before expanding it: a size, never a time).
    """
    n = model.scene.n
    if n > MAX_MASSES:
        return None
    s = sp.Symbol("s")
    C = model.C if model.C is not None else sp.zeros(n, n)
    Z = model.M * s**2 + C * s + model.K
    try:
        check(det_terms_bound(Z.applyfunc(sp.expand)), MAX_DET_TERMS)  # the cofactor is smaller
    except WorkCapExceeded:
        return None
    minor = Z.copy()
    minor.row_del(input)
    minor.col_del(output)
    cof = (-1) ** (input + output) * (minor.det(method="berkowitz") if n > 1 else sp.Integer(1))
    ratio = sp.cancel(sp.expand(cof) / sp.expand(Z.det(method="berkowitz")))
    num, den = sp.fraction(ratio)
    num, den = sp.collect(sp.expand(num), s), sp.collect(sp.expand(den), s)
    values = {model.params[k]: v for k, v in model.scene.parameters.items() if k in model.params}
    if model.rayleigh_targets is not None:  # α_R, β_R of [damping] rayleigh_targets
        from .rayleigh_targets import values as rayleigh_values

        values.update({s: float(v) for s, v in rayleigh_values(model).items()})
    names = model.scene.mass_names
    return TransferFunction(s, num, den, names[input], names[output], values)


__all__ = ["TransferFunction", "transfer_function", "MAX_MASSES"]
