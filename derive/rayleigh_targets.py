"""Rayleigh damping from target damping ratios at two modes: C = αM + βK with ζᵢ, ζⱼ prescribed.

Rayleigh damping gives every mode ζ(ω) = α/(2ω) + βω/2. Prescribing ζ_a at ω_a and ζ_b at ω_b
(two distinct elastic modes, counted from 1 in ascending ω as ``modes`` prints them) gives

    α = 2 ω_a ω_b (ζ_a ω_b − ζ_b ω_a) / ((ω_b − ω_a)(ω_b + ω_a)),
    β = 2 (ζ_b ω_b − ζ_a ω_a) / ((ω_b − ω_a)(ω_b + ω_a)),

and, for equal targets ζ_a = ζ_b = ζ, the cancellation-free α = 2ζ ω_a ω_b/(ω_a + ω_b),
β = 2ζ/(ω_a + ω_b).

The scene's ``[damping] rayleigh_targets = {zeta = [ζ_a, ζ_b], modes = [a, b]}`` enters the
model as two symbols α_R, β_R (:data:`ALPHA`, :data:`BETA`): the derivation reads
``- α_R*m*v_floor1 - β_R*(...)``, and their definition is printed beside it in closed form (from
the closed-form ω, where it exists; for equal targets, whose α and β are rationalised, within the work
caps :attr:`~derive.caps.Caps.rayleigh_ops` and :attr:`~derive.caps.Caps.rayleigh_radical_depth`) with the values. The values are computed on the accurate
route (the dynamical matrix assembled exactly, ``mpmath.eigsy`` at increasing precision until
α, β are settled to float64; past :data:`~derive.accurate.MAX_MPMATH_MODES` masses the
spring-factor SVD). The generated module computes them at call time from its own accurate
``omega2()`` (so other parameter values get their own α, β); its function bodies bind them
under private names (``_alpha_R``, ``_beta_R``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mpmath
import sympy as sp

from .printing import closed, latex

from .accurate import (MAX_DPS, MAX_MPMATH_MODES, eig_dynamical, certified, dynamical_bound, exact_values,
                       omega2_value, value)
from .caps import CAPS
from .errors import SceneError
from .work import ops, radical_depth
from .model_cache import cached_on

#: The model's symbols for the coefficients (non-ASCII: no parameter can take these names).
ALPHA = sp.Symbol("α_R", nonnegative=True)
BETA = sp.Symbol("β_R", nonnegative=True)
#: How LaTeX prints them (pdflatex has no α).
LATEX_NAMES = {ALPHA: r"\alpha_{R}", BETA: r"\beta_{R}"}
#: What generated code binds them to.
PRIVATE = {ALPHA: sp.Symbol("_alpha_R", real=True), BETA: sp.Symbol("_beta_R", real=True)}
KEY = "damping.rayleigh_targets"


@dataclass(frozen=True)
class RayleighFit:
    """α, β of Rayleigh damping meeting two target ratios, and the ζ it gives every mode.

    Attributes
    ----------
    alpha, beta : float
        Values at the scene's parameters (accurate route).
    alpha_expr, beta_expr : sympy.Expr or None
        Closed forms in the scene's parameters (None without closed-form modes).
    zeta_targets : (sympy.Expr, sympy.Expr)
    modes : (int, int)
        Elastic mode numbers, from 1.
    omega : tuple of float
        ω of every elastic mode (ascending).
    zeta : tuple of float
        ζ(ω) = α/(2ω) + βω/2 of every elastic mode.
    """

    alpha: float
    beta: float
    alpha_expr: sp.Expr | None
    beta_expr: sp.Expr | None
    zeta_targets: tuple
    modes: tuple
    omega: tuple
    zeta: tuple

    def to_json(self) -> dict:
        return {"alpha": self.alpha, "beta": self.beta,
                "alpha_expr": None if self.alpha_expr is None else sp.sstr(self.alpha_expr),
                "beta_expr": None if self.beta_expr is None else sp.sstr(self.beta_expr),
                "targets": {"zeta": [sp.sstr(z) for z in self.zeta_targets], "modes": list(self.modes)},
                "omega": list(self.omega), "zeta": list(self.zeta)}


def formula(wa, wb, za, zb, equal: bool, sqrt=None):
    """(α, β) from ω_a, ω_b and the targets (any number type; ``equal``: the targets are the same)."""
    if equal:
        return 2 * za * wa * wb / (wa + wb), 2 * za / (wa + wb)
    d = (wb - wa) * (wb + wa)
    return 2 * wa * wb * (za * wb - zb * wa) / d, 2 * (zb * wb - za * wa) / d


def _elastic_mp(model, dps: int):
    """Elastic ω² (ascending) at working precision ``dps`` or more: raised until every value is certified
    (:func:`accurate.certified`; two precisions can agree on the same deflated, wrong value)."""
    subs = exact_values(model.params, model.scene.parameters)
    masses = [m.xreplace(subs) for m in model.masses]
    springs = [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs]
    rigid, bound = len(model.free_components), dynamical_bound(masses, springs)
    while True:
        w2, _ = eig_dynamical(masses, springs, model.scene.n, dps)
        if certified(w2, rigid, bound, dps) or dps >= MAX_DPS:
            return w2[rigid:]
        dps *= 2


def _elastic_float(model):
    from .accurate import spring_factor_modes

    subs = exact_values(model.params, model.scene.parameters)
    masses = [m.xreplace(subs) for m in model.masses]
    springs = [(a, b, k.xreplace(subs)) for a, b, k, _, _ in model.springs]
    return [w for w, _ in spring_factor_modes(masses, springs, model.free_components)]


def _targets_value(model, targets, dps: int | None = None):
    subs = exact_values(model.params, model.scene.parameters)
    return [value(z, subs) for z in targets]


def fit_values(model, zeta_targets, modes) -> tuple[float, float, list[float]]:
    """(α, β, elastic ω) at the scene's values, settled to float64 (see module docstring).

    Raises
    ------
    SceneError
        When a mode number is out of range, the two modes have the same ω, or α or β < 0.
    """
    za, zb = _targets_value(model, zeta_targets)
    equal = sp.simplify(zeta_targets[0] - zeta_targets[1]) == 0
    a, b = modes
    if model.scene.n > MAX_MPMATH_MODES:
        w = [math.sqrt(max(x, 0.0)) for x in _elastic_float(model)]
        _check_modes(model, modes, len(w))
        if w[a - 1] == w[b - 1]:
            _same(model, modes, w[a - 1])
        alpha, beta = formula(w[a - 1], w[b - 1], za, zb, equal)
    else:
        prev = None
        dps = 40
        while True:
            with mpmath.workdps(dps):
                w2 = _elastic_mp(model, dps)
                _check_modes(model, modes, len(w2))
                wa, wb = mpmath.sqrt(w2[a - 1]), mpmath.sqrt(w2[b - 1])
                if abs(wa - wb) <= mpmath.mpf(10) ** (-(dps // 2)) * wb:
                    _same(model, modes, float(wa))
                fa, fb = formula(wa, wb, mpmath.mpf(za), mpmath.mpf(zb), equal)
                cur = (float(fa), float(fb), [float(mpmath.sqrt(x)) for x in w2])
            if prev is not None and all(abs(x - y) <= 1e-17 * max(abs(x), abs(y), 1e-300)
                                        for x, y in zip(prev[:2], cur[:2])) or dps > 640:
                break
            prev = cur
            dps *= 2
        alpha, beta, w = cur
    for name, v, why in (("alpha", alpha, "the higher mode"), ("beta", beta, "the lower mode")):
        if v < 0:
            raise SceneError(model.scene.file, KEY,
                             f"zeta = {[sp.sstr(z) for z in zeta_targets]} at modes {list(modes)}: gives {name} = "
                             f"{v:.6g} < 0 (negative damping: the target at {why} is too large for Rayleigh "
                             f"damping); accepted: targets with zeta_a*omega_b >= zeta_b*omega_a and "
                             f"zeta_b*omega_b >= zeta_a*omega_a (omega = {w[a - 1]:.6g}, {w[b - 1]:.6g})")
    return float(alpha), float(beta), [float(x) for x in w]


def _check_modes(model, modes, elastic: int) -> None:
    if not all(1 <= m <= elastic for m in modes):
        raise SceneError(model.scene.file, KEY, f"modes = {list(modes)}: the scene has {elastic} elastic modes; "
                                                f"accepted: two different mode numbers 1 ... {elastic}")


def _same(model, modes, w) -> None:
    raise SceneError(model.scene.file, KEY, f"modes = {list(modes)}: both have omega = {w:.10g} (a repeated "
                                            "frequency fixes no Rayleigh pair); accepted: two modes of "
                                            "different frequency")


def closed_form(model, mode_set, zeta_targets, modes) -> tuple[sp.Expr, sp.Expr] | None:
    """α, β in the scene's parameters from the closed-form ω (None without closed forms)."""
    if mode_set is None or not mode_set.closed_form:
        return None
    subs = exact_values(model.params, model.scene.parameters)
    elastic = sorted((m for m in mode_set.modes if not m.rigid for _ in m.shapes), key=lambda m: omega2_value(m, subs))
    if len(elastic) < max(modes):
        return None
    wa, wb = (sp.sqrt(elastic[m - 1].omega2) for m in modes)
    za, zb = zeta_targets
    equal = sp.simplify(za - zb) == 0
    alpha, beta = formula(wa, wb, za, zb, equal)
    if not equal:
        return alpha, beta
    # rationalising ω_a + ω_b squares sums of nested radicals: a work cap on its size, never a clock
    # (past it the values come from the accurate route alone, and the report's closed-form line says so)
    if ops(alpha) > CAPS.rayleigh_ops or radical_depth(wa + wb) > CAPS.rayleigh_radical_depth:
        return None
    return sp.factor(sp.radsimp(alpha)), sp.factor(sp.radsimp(beta))


def fit(model, mode_set, zeta_targets, modes) -> RayleighFit:
    """The :class:`RayleighFit` of ``zeta_targets`` at elastic ``modes`` (values, closed forms, ζ per mode)."""
    alpha, beta, w = fit_values(model, zeta_targets, modes)
    exprs = closed_form(model, mode_set, zeta_targets, modes)
    if exprs is not None:  # keep a closed form only where it agrees with the accurate values
        subs = exact_values(model.params, model.scene.parameters)
        ok = all(abs(value(e, subs) - v) <= 1e-12 * max(abs(v), 1e-300) for e, v in zip(exprs, (alpha, beta)))
        exprs = exprs if ok else None
    zeta = [alpha / (2 * x) + beta * x / 2 for x in w]
    return RayleighFit(alpha, beta, None if exprs is None else exprs[0], None if exprs is None else exprs[1],
                       tuple(zeta_targets), tuple(modes), tuple(w), tuple(zeta))


def values(model) -> dict:
    """``{ALPHA: Rational, BETA: Rational}`` at the scene's values (empty without targets): added to
    the exact parameter values wherever the derive side evaluates C."""
    t = getattr(model, "rayleigh_targets", None)
    if t is None:
        return {}
    cache = model.__dict__.setdefault("_rayleigh_fit_values", {})
    if not cache:
        from fractions import Fraction

        alpha, beta, _ = fit_values(model, *t)
        cache.update({ALPHA: sp.Rational(Fraction(alpha)), BETA: sp.Rational(Fraction(beta))})
    return dict(cache)


def model_fit(model, mode_set) -> RayleighFit | None:
    """The scene's own fit (None without ``rayleigh_targets``), cached on the model."""
    t = getattr(model, "rayleigh_targets", None)
    if t is None:
        return None
    return cached_on(model, "_rayleigh_fit", mode_set is not None, lambda: fit(model, mode_set, *t))


def text_lines(f: RayleighFit) -> list[str]:
    z = ", ".join(sp.sstr(x) for x in f.zeta_targets)
    out = [f"Rayleigh damping from targets zeta = ({z}) at modes {f.modes[0]} and {f.modes[1]}: C = α_R M + β_R K with",
           f"    α_R = {f.alpha:.10g}" + (f" = {closed(sp.sstr(f.alpha_expr))}" if f.alpha_expr is not None else ""),
           f"    β_R = {f.beta:.10g}" + (f" = {closed(sp.sstr(f.beta_expr))}" if f.beta_expr is not None else ""),
           "    zeta of every elastic mode, alpha/(2 omega) + beta omega/2: "
           + ", ".join(f"{j + 1}: {x:.6g}" for j, x in enumerate(f.zeta))]
    return out


def latex_lines(f: RayleighFit) -> list[str]:
    a = (latex(f.alpha_expr) + rf" \approx {f.alpha:.10g}") if f.alpha_expr is not None else f"{f.alpha:.10g}"
    b = (latex(f.beta_expr) + rf" \approx {f.beta:.10g}") if f.beta_expr is not None else f"{f.beta:.10g}"
    return [rf"\\ \alpha_R &= {a}, & \beta_R &= {b}"]


def binding_lines(model, kwcall: str) -> list[str]:
    """The body line that binds ``_alpha_R, _beta_R`` in a generated function (none without targets)."""
    if getattr(model, "rayleigh_targets", None) is None:
        return []
    return [f"    _alpha_R, _beta_R = rayleigh_coefficients({kwcall})"]


def private(expr):
    """``expr`` with α_R, β_R under the generated code's private names."""
    return expr.xreplace(PRIVATE) if hasattr(expr, "xreplace") else expr


def coefficients_lines(model, sig: str) -> list[str]:
    """``rayleigh_coefficients()`` of a scene with targets: computed at call time from ``omega2()``."""
    from .codeprint import p as _p

    (za, zb), (a, b) = model.rayleigh_targets
    kwcall = ", ".join(f"{p}={p}" for p in sig.split(", ")) if sig else ""
    equal = sp.simplify(za - zb) == 0
    out = ["", "", f"def rayleigh_coefficients({sig}):",
           f'    """(alpha, beta) of Rayleigh damping C = alpha*M + beta*K meeting zeta = ({sp.sstr(za)}, '
           f'{sp.sstr(zb)}) at elastic',
           f"    modes {a} and {b} ([damping] rayleigh_targets), from omega2() at these parameters, shape (2,).",
           '    """',
           f"    _w = numpy.sqrt(numpy.maximum(numpy.sort(omega2({kwcall})), 0.0))[_RIGID_MODES:]",
           f"    _wa, _wb = _w[{a - 1}], _w[{b - 1}]",
           f"    _za, _zb = {_p(za)}, {_p(zb)}"]
    if equal:
        out += ["    return numpy.array([2.0 * _za * _wa * _wb / (_wa + _wb), 2.0 * _za / (_wa + _wb)], dtype=float)"]
    else:
        out += ["    _d = (_wb - _wa) * (_wb + _wa)",
                "    return numpy.array([2.0 * _wa * _wb * (_za * _wb - _zb * _wa) / _d, "
                "2.0 * (_zb * _wb - _za * _wa) / _d], dtype=float)"]
    return out


__all__ = ["ALPHA", "BETA", "RayleighFit", "fit", "fit_values", "closed_form", "values", "model_fit",
           "text_lines", "latex_lines", "binding_lines", "private", "coefficients_lines", "formula"]
