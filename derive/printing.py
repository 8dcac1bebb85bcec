"""Printing expressions for people, in the scene's own notation.

* :func:`sstr` — SymPy's ``sstr``, but ``Mod(i, 2)`` printed as the scene language's ``i % 2`` (with
  the parentheses Python needs: ``2*(i % 2)``, ``(i % 2)**2``), so a user reads back what they wrote;
* :func:`latex` — SymPy's ``latex``, but names of several letters set upright (``\\mathrm{sum}``,
  not the product of italic s, u, m), as are multi-letter subscripts (``x_{\\mathrm{floor}1}``);
  Greek names stay Greek (``\\kappa``);
* :data:`MATRIX_LATEX`, :data:`MATRIX_TEXT` — the system matrices in bold (``\\mathbf{K}``, 𝐊), so
  they never read like a parameter named ``K``.

Only for reports: JSON fields keep SymPy's ``sstr`` (read back by ``parse_expression``).
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.conventions import split_super_sub
from sympy.printing.precedence import PRECEDENCE
from sympy.printing.str import StrPrinter

#: The matrices of the derivation, as LaTeX (bold) and as text (Unicode mathematical bold).
MATRIX_LATEX = {"M": r"\mathbf{M}", "K": r"\mathbf{K}", "C": r"\mathbf{C}", "D": r"\mathbf{D}"}
MATRIX_TEXT = {"M": "𝐌", "K": "𝐊", "C": "𝐂", "D": "𝐃"}


class ScenePrinter(StrPrinter):
    """``StrPrinter`` with ``Mod(a, b)`` as ``a % b``, parenthesised wherever Python would bind otherwise."""

    def _print_Mod(self, expr) -> str:
        a, b = expr.args
        # left-associative like * and /: a product on the left needs no parentheses, on the right it does
        return (f"{self.parenthesize(a, PRECEDENCE['Mul'], strict=True)} % "
                f"{self.parenthesize(b, PRECEDENCE['Mul'], strict=False)}")

    def _print_Mul(self, expr) -> str:
        c, rest = expr.as_coeff_Mul()
        if c == -1 and isinstance(rest, sp.Mod):  # -(i % 2): Python reads -i % 2 as (-i) % 2
            return f"-({self._print(rest)})"
        return super()._print_Mul(expr)

    def parenthesize(self, item, level, strict=False) -> str:
        # % binds like * and / (left to right): inside a product, a power or a Mod it needs parentheses
        # (SymPy asks with level "Add" for a product with a negative coefficient, so any level counts;
        # sums print their terms without asking, so i % 2 + 1 keeps none)
        if isinstance(item, sp.Mod):
            return f"({self._print(item)})"
        return super().parenthesize(item, level, strict)


def sstr(expr, **settings) -> str:
    """``sympy.sstr`` with ``%`` for ``Mod`` (see :class:`ScenePrinter`)."""
    return ScenePrinter(settings).doprint(expr)


def _piece(text: str) -> str:
    """One part of a name in LaTeX: a word of two letters or more (digits may follow) upright, unless
    SymPy gives it a meaning (Greek letters, accents such as ``xdot``)."""
    word = text.rstrip("0123456789")
    if len(word) >= 2 and word.isalpha() and sp.latex(sp.Symbol(word)) == word:
        return rf"\mathrm{{{word}}}{text[len(word):]}"
    return sp.latex(sp.Symbol(text))


def symbol_latex(name: str) -> str:
    """LaTeX for a symbol name: ``sum`` -> ``\\mathrm{sum}``, ``x_floor1`` -> ``x_{\\mathrm{floor1}}``,
    ``kappa`` -> ``\\kappa``, ``F0`` -> ``F_{0}``."""
    base, sups, subs = split_super_sub(name)
    tex = _piece(base) if base else ""
    if subs:
        tex += "_{" + " ".join(_piece(s) for s in subs) + "}"
    if sups:
        tex += "^{" + " ".join(_piece(s) for s in sups) + "}"
    return tex


def latex(expr, **settings) -> str:
    """``sympy.latex`` with every multi-letter name upright (:func:`symbol_latex`)."""
    symbols = getattr(expr, "free_symbols", set())
    names = {s: symbol_latex(s.name) for s in symbols if isinstance(s, sp.Symbol)}
    names.update(settings.pop("symbol_names", {}))
    return sp.latex(expr, symbol_names=names, **settings)


__all__ = ["sstr", "latex", "symbol_latex", "ScenePrinter", "MATRIX_LATEX", "MATRIX_TEXT"]
