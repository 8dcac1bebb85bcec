"""The symbolic half of ``springchain bands``: the unit cell, D(q), the characteristic polynomial, the closed-form
branches and cos q(ω²), as text, LaTeX and JSON (strings in SymPy's ``sstr``, read back by ``parse_expression``),
each expression beside its value at the scene's parameters where it has one.
"""

from __future__ import annotations

import sympy as sp

from ..printing import latex, sstr
from .dispersion import Dispersion
from ..expr import as_sympy


def _value(expr, values: dict) -> float | None:
    try:
        v = complex(sp.N(as_sympy(expr).subs(values), 17))
    except (TypeError, ValueError):
        return None
    return v.real if abs(v.imag) <= 1e-14 * max(abs(v.real), 1e-300) else None


def _end(cell, a: int, reach: int = 0) -> str:
    if a < 0:
        return "ground"
    return cell.names[a] + (f"{reach:+d}" if reach else "")


def _link_text(cell, s) -> str:
    return f"{_end(cell, s.a)} -> {_end(cell, s.b, s.reach)}"


def cell_json(d: Dispersion) -> dict:
    """The cell: masses and links with their expressions and values."""
    cell, values = d.cell, d.cell.values

    def link(s):
        return {"between": [_end(cell, s.a), _end(cell, s.b, s.reach)], "reach": s.reach, "key": s.key,
                "expr": sstr(s.k), "value": _value(s.k, values)}

    out = {"source": cell.source, "p": cell.size,
           "masses": [{"name": n, "expr": sstr(m), "value": _value(m, values)} for n, m in zip(cell.names, cell.masses)],
           "springs": [link(s) for s in cell.springs], "dampers": [link(s) for s in cell.dampers],
           "rayleigh": None if cell.rayleigh is None else [sstr(e) for e in cell.rayleigh]}
    return out


def symbolic_json(d: Dispersion) -> dict:
    """D(q), the polynomial, the closed forms (strings; null where none)."""
    s = lambda e: None if e is None else sstr(e)
    return {"dynamical_matrix": [[sstr(d.D[i, j]) for j in range(d.p)] for i in range(d.p)],
            "characteristic_polynomial": s(d.polynomial),
            "coefficients": None if d.coefficients is None else [sstr(c) for c in d.coefficients],
            "determinant": s(d.determinant),
            "closed_form": d.branches is not None,
            "omega2": None if d.branches is None else [sstr(b) for b in d.branches],
            "omega": None if d.frequencies is None else [sstr(w) for w in d.frequencies],
            "group_velocity": None if d.velocities is None else [sstr(v) for v in d.velocities],
            "cos_q": s(d.cos_q)}


def symbolic_lines(d: Dispersion) -> list[str]:
    """The text report's symbolic part."""
    cell, values = d.cell, d.cell.values
    lines = [f"Unit cell: {cell.source}; p = {cell.size} mass{'es' if cell.size > 1 else ''} per cell",
             "  masses: " + ", ".join(f"{n} = {sstr(m)} (= {_value(m, values):.10g})"
                                      for n, m in zip(cell.names, cell.masses))]
    for what, links in (("springs", cell.springs), ("dashpots", cell.dampers)):
        for s in links:
            v = _value(s.k, values)
            lines.append(f"  {what[:-1]} {_link_text(cell, s)}: {sstr(s.k)}" + (f" (= {v:.10g})" if v is not None else ""))
    if cell.rayleigh is not None:
        lines.append(f"  Rayleigh damping: C = {sstr(cell.rayleigh[0])}*M + {sstr(cell.rayleigh[1])}*K(q)")
    lines += ["", "Bloch matrix D(q) = M^-1/2 K(q) M^-1/2 (q: phase per cell, in [-pi, pi]; Hermitian):"]
    lines += ["    [" + ", ".join(sstr(d.D[i, j]) for j in range(d.p)) + "]" for i in range(d.p)]
    if d.polynomial is not None:
        lines += ["", "Characteristic polynomial det(K(q) - omega**2*M) = sum_j c_j*(-omega**2)**j, each c_j a sum of"
                      " positive terms:",
                  f"    det(K(q) - omega**2*M) = {sstr(d.polynomial)}"]
    elif d.determinant is not None:
        lines += ["", f"det K(q) = {sstr(d.determinant)}  (the polynomial is not expanded for p > 4)"]
    else:
        lines += ["", f"(det K(q) is not formed symbolically for a cell of {d.p} masses: the numbers below come from"
                      " the accurate numeric route)"]
    if d.branches is not None:
        lines += ["", "Closed-form branches (q in [0, pi]; even in q):"]
        for j, (b, w) in enumerate(zip(d.branches, d.frequencies)):
            lines += [f"    omega_{j}**2 = {sstr(b)}", f"    omega_{j}    = {sstr(w)}"]
    else:
        lines += ["", ("No closed-form branches (the polynomial does not factor into pieces of degree <= 2 in "
                       "omega**2): the numbers below come from the accurate numeric route.")]
    if d.cos_q is not None:
        lines += ["", "Complex band structure: cos q = " + sstr(d.cos_q),
                  "    (in a gap |cos q| > 1: Im q = arccosh|cos q| per cell, Re q = 0 or pi)"]
    return lines


def symbolic_latex(d: Dispersion) -> str:
    """D(q), the polynomial and the closed-form branches (amsmath)."""
    rows = [r"\mathbf{D}(q) &= " + latex(d.D)]
    if d.polynomial is not None:
        rows.append(r"\det\left(\mathbf{K}(q) - \omega^2 \mathbf{M}\right) &= " + latex(d.polynomial))
    if d.branches is not None:
        rows += [rf"\omega_{{{j}}}^2(q) &= " + latex(b) for j, b in enumerate(d.branches)]
    if d.cos_q is not None:
        rows.append(r"\cos q &= " + latex(d.cos_q))
    return "\\begin{align*}\n" + " \\\\\n".join(rows) + "\n\\end{align*}\n"


__all__ = ["cell_json", "symbolic_json", "symbolic_latex", "symbolic_lines"]
