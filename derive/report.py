"""The derivation printed for people (text) and for papers (LaTeX), and modes as JSON data.

Rendering only: every function returns a string or plain data; the command decides where it goes.
"""

from __future__ import annotations

from pathlib import Path

import sympy as sp

from .accurate import exact_values, omega2_value, value
from .model import Effect, Model
from .modes import ModeSet
from .closed_summary import closed_form_line, closed_form_parts
from .sag import sag_note, static_sag
from .printing import MATRIX_LATEX, MATRIX_TEXT, MAX_TEXT_CLOSED_FORM, ScenePrinter, closed, json_closed, latex, sstr
from .expr import as_sympy

MAX_MATRIX = 8  # larger matrices are described, not printed
#: Larger scenes print T, V, R as element sums (first ... last) and sums in stored order.
MAX_FULL_SUMS = 16


def _values(model: Model) -> dict:
    """Parameter symbols -> their values as exact rationals."""
    return exact_values(model.params, model.scene.parameters)


def _num(expr, model: Model) -> float:
    """``expr`` at the scene's values, correctly rounded to float64 (:func:`accurate.value`)."""
    if isinstance(expr, float):  # a numeric fallback's float64 shape component
        return expr
    expr = sp.Integer(expr) if isinstance(expr, int) else expr
    return value(expr, _values(model))


def _text(expr) -> str:
    """``sstr`` of an expression (``%`` for Mod); a Python float (a numeric fallback's shape) as its repr."""
    return repr(expr) if isinstance(expr, float) else sstr(expr)


def _pretty(mat: sp.Matrix) -> str:
    return sp.pretty(mat, use_unicode=True, wrap_line=False)


def _indent(text: str, pad: str = "    ") -> str:
    return "\n".join(pad + line for line in text.splitlines())


def _printer(model: Model):
    """``sstr`` for this scene's expressions. Past MAX_FULL_SUMS masses sums print in their stored
    order (``order="none"``): SymPy's display sort costs more than the whole derivation there."""
    if model.scene.n <= MAX_FULL_SUMS:
        return sstr
    return ScenePrinter({"order": "none"}).doprint


def equation_lines(model: Model) -> list[str]:
    """One line per mass: m ẍ = Σ forces, each traced to its scene entry."""
    show = _printer(model)
    by_mass: list[list] = [[] for _ in model.scene.mass_names]
    for t in model.terms:
        by_mass[t.coordinate].append(t)
    lines = []
    for i, terms in enumerate(by_mass):
        parts = []
        for j, t in enumerate(terms):
            text = show(t.force)
            if j:
                text = f"- {text[1:]}" if text.startswith("-") else f"+ {text}"
            parts.append(f"{text}  [{t.key}]")
        rhs = "   ".join(parts)
        lines.append(f"{show(model.masses[i])}*{model.a[i]} = {rhs or '0'}")
    return lines


def _energy_line(name: str, model: Model, terms: list, what: str) -> str:
    """``name = first + ... + last  (count terms: what)`` for a scene past MAX_FULL_SUMS masses."""
    show = _printer(model)
    if not terms:
        return f"{name} = 0"
    first, last = show(terms[0]), show(terms[-1])
    last = f"- {last[1:]}" if last.startswith("-") else f"+ {last}"
    return f"{name} = {first} + ... {last}   ({len(terms)} terms: {what})"


def _energy_lines(model: Model) -> list[str]:
    """The T, V (and R) lines of the text report: in full, or element sums past MAX_FULL_SUMS masses."""
    if model.scene.n <= MAX_FULL_SUMS:
        out = [f"T = {sstr(model.T)}", f"V = {sstr(model.V)}"]
        if model.dissipation_terms:
            out.append(f"R = {sstr(model.R)}   (Rayleigh dissipation)")
        return out
    v_terms = [e for key, e in model.potential_terms if key != "gravity"]
    if model.g is not None:
        v_terms += [-m * model.g * x for m, x in zip(model.masses, model.x)]
    out = [_energy_line("T", model, [e for _, e in model.kinetic_terms], "one per mass"),
           _energy_line("V", model, v_terms, "one per spring" + (", one per mass for gravity"
                                                                 if model.g is not None else ""))]
    if model.dissipation_terms:
        out.append(_energy_line("R", model, [e for _, e in model.dissipation_terms], "one per dissipation term")
                   + "   (Rayleigh dissipation)")
    return out


def shape_values(model: Model, shape) -> list[float]:
    """A shape's components at the scene's values (correctly rounded), zeros told by a floor.

    A closed-form shape's first nonzero component is 1 (its scale); a component j counts as 0 once
    it is certainly below 1e-20 of that in the mass-weighted sense (``1e-20·sqrt(m_pivot/m_j)``),
    never by the noise heuristic alone (a component 0.618 computed from terms of 1e269 was printed
    as 0). Numeric fallback shapes are floats already.
    """
    subs = _values(model)
    pivot = next((i for i, c in enumerate(shape) if not isinstance(c, float) and as_sympy(c).is_Number
                  and c != 0), None)
    if pivot is None:
        return [_num(c, model) for c in shape]
    masses = [value(m, subs) for m in model.masses]
    scale = abs(float(shape[pivot])) * masses[pivot] ** 0.5
    return [c if isinstance(c, float) else value(as_sympy(c), subs, floor=1e-20 * scale / masses[j] ** 0.5)
            for j, c in enumerate(shape)]


def mode_records(model: Model, modes: ModeSet) -> list[dict]:
    """One record per independent mode (a repeated ω² once per shape), sorted by value."""
    out = []
    for mode in modes.modes:
        for shape in mode.shapes:
            out.append({
                "omega2": sp.sstr(mode.omega2),
                "omega2_value": omega2_value(mode, _values(model)),
                "multiplicity": mode.multiplicity,
                "shape": [_text(c) for c in shape],
                "shape_value": shape_values(model, shape),
            })
    out.sort(key=lambda r: r["omega2_value"])
    return out


def equilibrium_json(model: Model) -> dict | None:
    """``{"x", "x_value", "closed_form", "how", "stable", "springs": [{"key", "extension", "stiffness", ...}]}``
    for a scene with potentials, else None. Strings are SymPy's ``sstr`` (numbers for a numeric one);
    ``stable`` is always true: an equilibrium that is not stable (some V''(d) ≤ 0) is refused."""
    eq = model.equilibrium
    if eq is None:
        return None
    springs = []
    for (a, b, *_), law, d, k in zip(model.springs, model.laws, eq.extensions, eq.stiffness):
        springs.append({"key": law.key, "potential": sstr(law.energy) if law.given else None,
                        "extension": sstr(d), "extension_value": _num(d, model),
                        "stiffness": sstr(k), "stiffness_value": value(k, _values(model), nonzero=True)})
    return {"x": [sstr(v) for v in eq.x], "x_value": [_num(v, model) for v in eq.x],
            "closed_form": eq.closed_form, "how": eq.how, "stable": True, "springs": springs}


def equilibrium_lines(model: Model) -> list[str]:
    """The static equilibrium for the text report (scenes with potentials)."""
    eq = model.equilibrium
    if eq is None:
        return []
    out = ["Static equilibrium (gradient of V and constant loads = 0): x_eq = ("
           + ", ".join(sstr(v) for v in eq.x) + ")",
           f"    found by: {eq.how}"]
    for law, d, k in zip(model.laws, eq.extensions, eq.stiffness):
        out.append(f"    {law.key}: extension d = {sstr(d)}, stiffness V''(d) = {sstr(k)}"
                   + (f"  (= {value(k, _values(model), nonzero=True):.10g})" if not k.is_Number else ""))
    return out


def modes_json(model: Model, modes: ModeSet) -> dict:
    sc = model.scene
    records = mode_records(model, modes)
    extra = {}
    if model.equilibrium is not None:
        extra["equilibrium"] = equilibrium_json(model)
    if model.damped:
        from .damping_report import damped_modes, json_fields

        extra.update(json_fields(damped_modes(model, modes), records))
        if model.rayleigh_targets is not None:
            from .rayleigh_targets import model_fit

            extra["damping"]["rayleigh_coefficients"] = model_fit(model, modes).to_json()
    from . import participation as part

    if part.applies(model):
        extra.update(part.json_fields(part.participation(model, modes), records))
    notes = list(modes.notes) + effect_notes(model)
    _cap_closed_forms(records, extra, notes)
    return {
        "scene": sc.name,
        "parameters": {k: sc.parameters[k] for k in sorted(sc.parameters)},
        "masses": list(sc.mass_names),
        "modes": records,
        "closed_form": modes.closed_form,
        "closed_form_parts": (parts := closed_form_parts(model, modes)),
        "closed_form_summary": closed_form_line(parts),
        "notes": notes,
        **extra,
    }


#: The closed-form fields of a ``modes --json`` record (each beside its value field).
_RECORD_FORMS = ("omega2", "damping_ratio_expr", "participation_factor_expr", "effective_mass_expr")


def _cap_closed_forms(records: list[dict], extra: dict, notes: list) -> None:
    """Null (with a note) every closed form past :data:`printing.MAX_JSON_CLOSED_FORM` characters, in place:
    the fields stay, their values become None (a shape as a whole)."""
    for j, rec in enumerate(records, start=1):
        for key in _RECORD_FORMS:
            if isinstance(rec.get(key), str):
                rec[key] = json_closed(rec[key], f"modes[{j - 1}].{key}", notes)
        if isinstance(rec.get("shape"), list) and rec["shape"]:
            if json_closed(", ".join(rec["shape"]), f"modes[{j - 1}].shape", notes) is None:
                rec["shape"] = None
    fit = extra.get("damping", {}).get("rayleigh_coefficients")
    for key in ("alpha_expr", "beta_expr"):
        if fit is not None and isinstance(fit.get(key), str):
            fit[key] = json_closed(fit[key], f"damping.rayleigh_coefficients.{key}", notes)


def static_equilibrium(model: Model) -> list[sp.Expr] | None:
    """x_eq = K⁻¹ M g for a scene with gravity and no free piece (None otherwise): the closed form
    within the caps, else the exact rational values at the scene's parameters (:mod:`derive.sag`)."""
    sag = static_sag(model)
    if sag is None:
        return None
    if sag.closed is not None:
        return list(sag.closed)
    return list(sag.exact) if sag.exact is not None else [sp.Float(v, 17) for v in sag.values]


def effect_notes(model: Model) -> list[str]:
    """Plain-language notes on the effects a scene declares."""
    notes = []
    if model.equilibrium is not None:
        what = ("cubic springs under constant loads (each as its energy k d^2/2 + k3 d^4/4)"
                if any(law.cubic for law in model.laws) and not model.scene.has_potential else "spring potentials")
        notes.append(f"{what}: modes are those of the linearisation about the static equilibrium "
                     "x_eq (K = Hessian of V there); the exact modal solution does not apply (integrators only)"
                     if not model.linear else "spring potentials: all quadratic with V'(0) = 0, i.e. linear springs")
    if model.g is not None and model.equilibrium is None:
        sag = static_sag(model)
        if sag is not None:
            notes.append(sag_note(sag))
        elif model.free_components:
            notes.append("gravity: a free piece has no equilibrium; its centre of mass accelerates: "
                         "x_cm(t) = x_cm0 + v_cm*t + g*t**2/2 (the exact solution includes it)")
    if Effect.CUBIC in model.effects:
        notes.append("cubic springs: modes are those of the linearization about x = 0; "
                     "the exact modal solution does not apply (integrators only)")
    if model.forces:
        from .forcing import harmonics_by_mass

        if harmonics_by_mass([(on, f) for on, f, _ in model.forces], model.t) is None:
            notes.append("forces are not constant + harmonic in t: no exact solution; integrators only")
        else:
            notes.append("forces are constant + harmonic: exact solution = steady state "
                         "(K - Omega^2 M + i Omega C)^-1 F + transient")
    notes += _load_notes(model)
    if model.damped:
        from .damping_report import damped_modes

        prop = damped_modes(model, None).proportional
        notes.append("damping is proportional (real modes, zeta_j = phi_j.C.phi_j / (2 omega_j))" if prop
                     else "damping is not proportional: complex modes (state-space eigenvalues)")
    return notes


def _load_notes(model: Model) -> list[str]:
    """Notes on tabulated forces and ground motion (coordinates relative to the ground)."""
    notes = [f"{key}: f_table{key[7:-1]}(t) is the table {Path(tf.table.file).name} "
             f"({tf.table.t.shape[0]} rows, t = {tf.table.t[0]:g} ... {tf.table.t[-1]:g}), linear "
             "between rows, zero outside"
             for (_, _, key), tf in zip(model.table_forces, model.scene.table_forces)]
    ground = model.scene.ground
    if ground is not None:
        what = (f"a_g(t) = {sstr(model.ground)}" if model.ground is not None else
                f"a_g(t) is the table {Path(ground.table.file).name} ({ground.table.t.shape[0]} rows), "
                "linear between rows, zero outside")
        notes.append(f"ground: {what}; coordinates are relative to the ground (walls move with it)")
        if model.ground_motion is not None:
            notes.append(f"ground: x_g(t) = {sstr(model.ground_motion[1])} (x_g(0) = v_g(0) = 0)")
    return notes


def mode_lines(model: Model, modes: ModeSet) -> list[str]:
    lines = []
    for mode in modes.modes:
        value = omega2_value(mode, _values(model))
        tag = "  rigid-body: uniform translation of a free piece" if mode.rigid else ""
        mult = f"  (multiplicity {mode.multiplicity})" if mode.multiplicity > 1 else ""
        text = sstr(mode.omega2)
        if len(text) <= MAX_TEXT_CLOSED_FORM:
            lines.append(f"ω² = {text}   (= {value:.10g} at the scene's values){mult}{tag}")
        else:
            lines.append(f"ω² = {value:.10g} at the scene's values   {closed(text)}{mult}{tag}")
        for s in mode.shapes:
            text = ", ".join(_text(c) for c in s)
            if len(text) <= MAX_TEXT_CLOSED_FORM:
                lines.append(f"    shape ({text})")
            else:
                lines.append(f"    shape ({', '.join(f'{_num(c, model):.10g}' for c in s)}) at the scene's values   "
                             f"{closed(text)}")
    return lines


def render_text(model: Model, modes: ModeSet) -> str:
    """The derivation as plain text."""
    sc = model.scene
    n = sc.n
    out = [f"Scene {sc.name!r} ({sc.file}): {sc.description}".rstrip(": "),
           "Parameters: " + ", ".join(f"{k} = {sc.parameters[k]:g}" for k in sorted(sc.parameters)),
           "Coordinates: " + ", ".join(str(x) for x in model.x)
           + " (displacements from the springs' rest configuration)",
           "", *_energy_lines(model)]
    M, K, C, D = (MATRIX_TEXT[k] for k in "MKCD")  # bold: never read like a parameter named K
    lhs = f"{M} x''" + (f" + {C} x'" if model.damped else "") + (
        " + grad V(x)" if Effect.POTENTIAL in model.effects else f" + {K} x") + (
        " + f_nl(x)" if Effect.CUBIC in model.effects else "")
    rhs = " + ".join([*(["F(t)"] if model.forces else []), *(["F_table(t)"] if model.table_forces else []),
                      *([f"{M} g"] if model.g is not None else [])]) or "0"
    if sc.ground is not None:
        rhs = ("" if rhs == "0" else rhs + " ") + f"- {M} 1 a_g(t)"
    out += ["L = T - V", "", f"Equations of motion: {lhs} = {rhs}",
            "Per mass (Euler-Lagrange; each term traced to its scene entry):"]
    out += ["    " + line for line in equation_lines(model)]
    if model.equilibrium is not None:
        out += [""] + equilibrium_lines(model)
    if n <= MAX_MATRIX:
        out += ["", f"{M} = d²T/dv² (mass matrix) =", _indent(_pretty(model.M)), "",
                f"{K} = d²V/dx² (stiffness matrix{' at x_eq' if model.equilibrium is not None else ''}) =",
                _indent(_pretty(model.K))]
        if model.C is not None:
            out += ["", f"{C} = d²R/dv² (damping matrix) =", _indent(_pretty(model.C))]
        if model.rayleigh_targets is not None:
            from .rayleigh_targets import model_fit, text_lines as rayleigh_lines

            out += [""] + rayleigh_lines(model_fit(model, modes))
        if model.modal_zeta is not None:
            out += ["", (f"{C} += " if model.C is not None else f"{C} = ") + f"{M} Φ diag(2 ζ_j ω_j) Φᵀ {M}  (modal "
                    "damping, ζ = (" + ", ".join(sstr(z) for z in model.modal_zeta) + "); Φ the M-orthonormal modes; "
                    "numeric: damping_matrix() of the generated module)"]
        out += ["", f"{D} = {M}^-1/2 {K} {M}^-1/2 (dynamical matrix) =", _indent(_pretty(model.D))]
    else:
        out += ["", f"{M}, {K}, {D}: {n}x{n} (not printed; see the generated module)"]
    if Effect.CUBIC in model.effects:
        out += ["", "Nonlinear (cubic) springs: the modes below are those of the linearization "
                    "about x = 0; the exact modal solution does not apply."]
    out += ["", f"Normal modes, {K} φ = ω² {M} φ (shapes in physical coordinates, any scale):"]
    out += ["    " + line for line in mode_lines(model, modes)]
    out += [f"    note: {note}" for note in modes.notes]
    if model.damped:
        from .damping_report import damped_modes, damped_mode_lines

        out += [""] + damped_mode_lines(model, damped_modes(model, modes))
    from . import participation as part

    if part.applies(model):
        out += [""] + part.text_lines(part.participation(model, modes))
    notes = effect_notes(model)
    if notes:
        out += [""] + [f"{n}" for n in notes]
    out += ["", closed_form_line(closed_form_parts(model, modes))]
    return "\n".join(out) + "\n"


def render_latex(model: Model, modes: ModeSet) -> str:
    """The derivation as a LaTeX fragment (amsmath)."""
    from functools import partial

    from .rayleigh_targets import LATEX_NAMES

    # multi-letter names upright; the matrices bold (never like a parameter named K); α_R, β_R of
    # rayleigh_targets as \alpha_{R}, \beta_{R}
    L = partial(latex, symbol_names=LATEX_NAMES)
    M, K, D = MATRIX_LATEX["M"], MATRIX_LATEX["K"], MATRIX_LATEX["D"]
    lines = [r"\begin{align*}",
             rf"T &= {L(model.T)} \\",
             rf"V &= {L(model.V)} \\"]
    if model.dissipation_terms:
        lines.append(rf"R &= {L(model.R)} \\")
    for i in range(len(model.scene.mass_names)):  # as the text: m_i a_i = the traced forces
        rhs = sp.Add(*(t.force for t in model.terms if t.coordinate == i))
        lines.append(rf"{L(model.masses[i] * model.a[i])} &= {L(rhs)} \\")
    if model.equilibrium is not None:
        lines.append(rf"x_{{\mathrm{{eq}}}} &= {L(sp.Matrix(model.equilibrium.x).T)} \\")
    lines += [rf"{M} &= {L(model.M)} \\", rf"{K} &= {L(model.K)} \\",
              rf"{D} &= {M}^{{-1/2}} {K} {M}^{{-1/2}} = {L(model.D)}"]
    for mode in modes.modes:
        for s in mode.shapes:
            lines.append(rf"\\ \omega^2 &= {L(mode.omega2)}, & \phi &= {L(sp.Matrix(s).T)}")
    if model.damped:
        from .damping_report import damped_modes, latex_lines

        lines += latex_lines(damped_modes(model, modes))
    if model.rayleigh_targets is not None:
        from .rayleigh_targets import latex_lines as rayleigh_latex, model_fit

        lines += rayleigh_latex(model_fit(model, modes))
    from . import participation as part

    if part.applies(model):
        lines += part.latex_lines(part.participation(model, modes))
    lines.append(r"\end{align*}")
    return "\n".join(lines) + "\n"
