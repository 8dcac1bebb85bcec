"""The derivation printed for people (text) and for papers (LaTeX), and modes as JSON data.

Rendering only: every function returns a string or plain data; the command decides where it goes.
"""

from __future__ import annotations

import sympy as sp

from .model import Effect, Model
from .modes import ModeSet

MAX_MATRIX = 8  # larger matrices are described, not printed


def _values(model: Model) -> dict:
    return {model.params[k]: v for k, v in model.scene.parameters.items()}


def _num(expr, model: Model) -> float:
    return float(sp.re(sp.N(sp.sympify(expr).subs(_values(model)), 17)))


def _pretty(mat: sp.Matrix) -> str:
    return sp.pretty(mat, use_unicode=True, wrap_line=False)


def _indent(text: str, pad: str = "    ") -> str:
    return "\n".join(pad + line for line in text.splitlines())


def equation_lines(model: Model) -> list[str]:
    """One line per mass: m ẍ = Σ forces, each traced to its scene entry."""
    lines = []
    for i, name in enumerate(model.scene.mass_names):
        terms = [t for t in model.terms if t.coordinate == i]
        rhs = "   ".join(f"{'+' if j else ''}{sp.sstr(t.force)}  [{t.key}]" for j, t in enumerate(terms))
        lines.append(f"{sp.sstr(model.masses[i])}*{model.a[i]} = {rhs or '0'}")
    return lines


def mode_records(model: Model, modes: ModeSet) -> list[dict]:
    """One record per independent mode (a repeated ω² once per shape), sorted by value."""
    out = []
    for mode in modes.modes:
        for shape in mode.shapes:
            out.append({
                "omega2": sp.sstr(mode.omega2),
                "omega2_value": max(_num(mode.omega2, model), 0.0) if mode.rigid else _num(mode.omega2, model),
                "multiplicity": mode.multiplicity,
                "shape": [sp.sstr(c) for c in shape],
                "shape_value": [_num(c, model) for c in shape],
            })
    out.sort(key=lambda r: r["omega2_value"])
    return out


def modes_json(model: Model, modes: ModeSet) -> dict:
    sc = model.scene
    return {
        "scene": sc.name,
        "parameters": {k: sc.parameters[k] for k in sorted(sc.parameters)},
        "masses": list(sc.mass_names),
        "modes": mode_records(model, modes),
        "closed_form": modes.closed_form,
        "notes": list(modes.notes),
    }


def mode_lines(model: Model, modes: ModeSet) -> list[str]:
    lines = []
    for mode in modes.modes:
        value = _num(mode.omega2, model)
        tag = "  rigid-body: uniform translation of a free piece" if mode.rigid else ""
        mult = f"  (multiplicity {mode.multiplicity})" if mode.multiplicity > 1 else ""
        lines.append(f"ω² = {sp.sstr(mode.omega2)}   (= {value:.10g} at the scene's values){mult}{tag}")
        for s in mode.shapes:
            lines.append(f"    shape ({', '.join(sp.sstr(c) for c in s)})")
    return lines


def render_text(model: Model, modes: ModeSet) -> str:
    """The derivation as plain text."""
    sc = model.scene
    n = sc.n
    out = [f"Scene {sc.name!r} ({sc.file}): {sc.description}".rstrip(": "),
           "Parameters: " + ", ".join(f"{k} = {sc.parameters[k]:g}" for k in sorted(sc.parameters)),
           "Coordinates: " + ", ".join(str(x) for x in model.x)
           + " (displacements from the springs' rest configuration)",
           "",
           f"T = {sp.sstr(model.T)}",
           f"V = {sp.sstr(model.V)}"]
    if model.dampers:
        out.append(f"R = {sp.sstr(model.R)}   (Rayleigh dissipation)")
    out += [f"L = T - V", "", "Equations of motion (Euler-Lagrange; each term traced to its scene entry):"]
    out += ["    " + line for line in equation_lines(model)]
    if n <= MAX_MATRIX:
        out += ["", "M = d²T/dv² =", _indent(_pretty(model.M)), "",
                "K = d²V/dx² =", _indent(_pretty(model.K))]
        if model.C is not None:
            out += ["", "C = d²R/dv² =", _indent(_pretty(model.C))]
        out += ["", "D = M^-1/2 K M^-1/2 =", _indent(_pretty(model.D))]
    else:
        out += ["", f"M, K, D: {n}x{n} (not printed; see the generated module)"]
    if Effect.CUBIC in model.effects:
        out += ["", "Nonlinear (cubic) springs: the modes below are those of the linearization "
                    "about x = 0; the exact modal solution does not apply."]
    out += ["", "Normal modes, K φ = ω² M φ (shapes in physical coordinates, any scale):"]
    out += ["    " + line for line in mode_lines(model, modes)]
    out += [f"    note: {note}" for note in modes.notes]
    return "\n".join(out) + "\n"


def render_latex(model: Model, modes: ModeSet) -> str:
    """The derivation as a LaTeX fragment (amsmath)."""
    L = sp.latex
    lines = [r"\begin{align*}",
             rf"T &= {L(model.T)} \\",
             rf"V &= {L(model.V)} \\"]
    if model.dampers:
        lines.append(rf"R &= {L(model.R)} \\")
    lhs = model.euler_lagrange()
    for i, e in enumerate(lhs):
        lines.append(rf"0 &= {L(e)} \\")
    lines += [rf"M &= {L(model.M)} \\", rf"K &= {L(model.K)} \\",
              rf"D &= M^{{-1/2}} K M^{{-1/2}} = {L(model.D)}"]
    for mode in modes.modes:
        for s in mode.shapes:
            lines.append(rf"\\ \omega^2 &= {L(mode.omega2)}, & \phi &= {L(sp.Matrix(s).T)}")
    lines.append(r"\end{align*}")
    return "\n".join(lines) + "\n"
