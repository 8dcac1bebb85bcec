"""Printing expressions for people, in the scene's own notation.

* :func:`sstr` — SymPy's ``sstr``, but ``Mod(i, 2)`` printed as the scene language's ``i % 2`` (with
  the parentheses Python needs: ``2*(i % 2)``, ``(i % 2)**2``), so a user reads back what they wrote;
* :func:`latex` — SymPy's ``latex``, but names of several letters set upright (``\\mathrm{sum}``,
  not the product of italic s, u, m), as are multi-letter subscripts (``x_{\\mathrm{floor}1}``);
  Greek names stay Greek (``\\kappa``);
* :data:`MATRIX_LATEX`, :data:`MATRIX_TEXT` — the system matrices in bold (``\\mathbf{K}``, 𝐊), so
  they never read like a parameter named ``K``.

Only for reports: JSON fields keep SymPy's ``sstr`` (read back by ``parse_expression``).

**Size caps of printed closed forms** (characters of the printed text, measured after printing, so
they cost nothing): a text report prints a closed form of at most :data:`MAX_TEXT_CLOSED_FORM`
characters and shows a longer one by its value with :func:`closed`'s note; ``--json`` carries closed
forms of at most :data:`MAX_JSON_CLOSED_FORM` characters and a longer one is null, with a note
(:func:`json_closed`). A three-mass chain of unequal masses has ω² of ~75 characters but shapes, ζ,
Γ, M*, α_R and β_R of 170–650, which the text report now names instead of printing.
"""

from __future__ import annotations

import sympy as sp

from sympy.printing.conventions import split_super_sub
from sympy.printing.precedence import PRECEDENCE
from sympy.printing.str import StrPrinter

from .caps import CAPS

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


#: Longest closed form a text report prints (characters, about two terminal lines).
MAX_TEXT_CLOSED_FORM = CAPS.text_closed_form
#: Longest closed form a ``--json`` field carries (characters); a longer one is null, with a note.
MAX_JSON_CLOSED_FORM = CAPS.json_closed_form


def closed(text: str) -> str:
    """``text`` (a printed closed form) if it is at most :data:`MAX_TEXT_CLOSED_FORM` characters long,
    else the note a text report prints in its place."""
    if len(text) <= MAX_TEXT_CLOSED_FORM:
        return text
    where = "--json carries it" if len(text) <= MAX_JSON_CLOSED_FORM else "too long for --json as well"
    return f"(closed form omitted: {len(text)} characters; {where})"


def json_closed(text: str | None, what: str, notes: list) -> str | None:
    """``text`` for a ``--json`` field, or None (with a note appended to ``notes``) past
    :data:`MAX_JSON_CLOSED_FORM` characters."""
    if text is None or len(text) <= MAX_JSON_CLOSED_FORM:
        return text
    notes.append(f"{what}: closed form of {len(text)} characters omitted (null; the limit is "
                 f"{MAX_JSON_CLOSED_FORM}); the value is in the value field")
    return None


__all__ = ["sstr", "latex", "symbol_latex", "ScenePrinter", "MATRIX_LATEX", "MATRIX_TEXT", "MAX_TEXT_CLOSED_FORM",
           "MAX_JSON_CLOSED_FORM", "closed", "json_closed"]
