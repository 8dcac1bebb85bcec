"""The one line of a ``modes`` report that says which parts are closed-form (the rest: numeric values).

Every symbolic step runs under a deterministic work cap (:mod:`derive.caps`); past it the value comes
from the accurate numeric route (mpmath settled to float64, exact rational solves, the spring-factor
SVD). This module counts what stayed closed-form, from the objects the report already computed
(cached on the model: no work is done twice), and says it in one line::

    closed form: ω² and shapes of 3 of 3 modes, static sag x_eq, ζ of 3 of 3 modes; values only (at the
    scene's parameters, accurate to float64): Γ, M*
"""

from __future__ import annotations

from .model import Model
from .modes import ModeSet


def closed_form_parts(model: Model, modes: ModeSet) -> dict:
    """What is closed-form, per part of the report.

    Returns
    -------
    dict
        ``{"modes": [closed, total], "sag": bool, "equilibrium": bool, "damping_ratios": [closed, total],
        "participation": [closed, total], "rayleigh_fit": bool}``, a part present only where the
        scene has it; ``[closed, total]`` counts independent modes (a repeated ω² once per shape).
    """
    out: dict = {}
    shapes = [(mode, s) for mode in modes.modes for s in mode.shapes]
    out["modes"] = [sum(1 for mode, _ in shapes if mode.exact and modes.closed_form), len(shapes)]
    if model.equilibrium is not None:
        out["equilibrium"] = bool(model.equilibrium.closed_form)
    elif model.g is not None:
        from .sag import static_sag

        sag = static_sag(model)
        if sag is not None:
            out["sag"] = sag.closed is not None
    if model.damped:
        from .damping_report import damped_modes

        rows = [r for r in damped_modes(model, modes).rows if r.zeta is not None]
        out["damping_ratios"] = [sum(1 for r in rows if r.zeta_expr is not None), len(rows)]
        if model.rayleigh_targets is not None:
            from .rayleigh_targets import model_fit

            fit = model_fit(model, modes)
            out["rayleigh_fit"] = fit is not None and fit.alpha_expr is not None and fit.beta_expr is not None
    from . import participation as part

    if part.applies(model):
        p = part.participation(model, modes)
        out["participation"] = [sum(1 for g in p.gamma_expr if g is not None), len(p.gamma_expr)]
    return out


_NAMES = {"modes": "ω² and shapes", "sag": "static sag x_eq", "equilibrium": "equilibrium x_eq",
          "damping_ratios": "ζ", "participation": "Γ, M*", "rayleigh_fit": "Rayleigh α_R, β_R"}


def closed_form_line(parts: dict) -> str:
    """``closed form: ...`` from :func:`closed_form_parts` (one line): the parts with a closed form (counts of
    modes where some are), then those given as values only."""
    have, lack = [], []
    for key, v in parts.items():
        name = _NAMES[key]
        if isinstance(v, bool):
            (have if v else lack).append(name)
        elif v[1]:
            if v[0]:
                have.append(f"{name} of {v[0]} of {v[1]} modes")
            else:
                lack.append(name)
    text = "closed form: " + (", ".join(have) if have else "none")
    if lack:
        text += "; values only (at the scene's parameters, accurate to float64): " + ", ".join(lack)
    return text


__all__ = ["closed_form_parts", "closed_form_line"]
