"""SymPy expressions printed as NumPy source text: the one printer every section writer uses.

The lowest layer of code generation: it knows SymPy's printer and nothing of scenes or modules,
so :mod:`derive.module_text`, :mod:`derive.codegen`, :mod:`derive.chain_codegen` and the effect
writers (:mod:`derive.loadgen`, :mod:`derive.damping_code`, :mod:`derive.chain_damping_code`)
all import it and none of them imports another renderer for a helper. Text printed here says
``numpy.``; :func:`derive.module_text.privatize` turns that into the module's private ``_np.``.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.numpy import NumPyPrinter


class _Printer(NumPyPrinter):
    """NumPy printer that names symbols as they are (scene names are never keywords) and
    never prints a Python builtin (``abs``), so that a parameter may take any such name."""

    def _print_Symbol(self, expr):
        return expr.name

    def _print_Abs(self, expr):
        return f"numpy.abs({self._print(expr.args[0])})"

    def _print_expm1mx(self, expr):  # derive.stable_laws: exp(z) - 1 - z, a private helper of the module
        return f"_expm1mx({self._print(expr.args[0])})"

    def _print_log1pmx(self, expr):  # log(1 + z) - z
        return f"_log1pmx({self._print(expr.args[0])})"


def _printer() -> NumPyPrinter:
    return _Printer({"fully_qualified_modules": True, "allow_unknown_functions": False})


def p(expr) -> str:
    """Print a SymPy expression (or a Python int, e.g. 0) as NumPy code."""
    return _printer().doprint(sp.Integer(expr) if isinstance(expr, int) else expr)


def array(entries: list[str]) -> str:
    """A float array literal of already printed entries (``numpy.zeros(0)`` when empty)."""
    if not entries:
        return "numpy.zeros(0)"
    return "numpy.array([" + ", ".join(entries) + "], dtype=float)"


def matrix(mat: sp.Matrix) -> str:
    """A float (R, C) array literal of a SymPy matrix (parameters only), one row a line."""
    rows = ["[" + ", ".join(p(mat[i, j]) for j in range(mat.shape[1])) + "]" for i in range(mat.shape[0])]
    return "numpy.array([\n        " + ",\n        ".join(rows) + ",\n    ], dtype=float)"


__all__ = ["p", "array", "matrix"]
