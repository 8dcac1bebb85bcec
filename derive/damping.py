"""The scene table ``[damping]``: Rayleigh (``C = αM + βK``) or modal (ratios ζⱼ per mode).

Checked at the boundary like every scene table (:class:`~derive.scene_loader.Loader`): exactly
one of the two keys; coefficients are whitelisted expressions of the parameters (or numbers),
finite and ≥ 0 at the scene's values, not all 0; a list of modal ratios has exactly one entry
per mode (``N`` of them, rigid-body modes included, in ascending ω order). SymPy is not
imported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .expr import Expr
from .scene_loader import MAX_MAGNITUDE, Loader

DAMPING_KEYS = ("rayleigh", "modal")
_FORM = "exactly one of rayleigh = [ALPHA, BETA] or modal = ZETA or modal = [ZETA_1, ..., ZETA_N]"


@dataclass(frozen=True)
class DampingModel:
    """A declared damping model.

    Attributes
    ----------
    rayleigh : (Expr, Expr) or None
        ``(α, β)`` of ``C = αM + βK``.
    modal : tuple of Expr or None
        Damping ratios ζⱼ in ascending ω order: one entry (every mode alike) or one per mode.
    """

    rayleigh: tuple[Expr, Expr] | None = None
    modal: tuple[Expr, ...] | None = None

    @property
    def kind(self) -> str:
        """``"rayleigh"`` or ``"modal"``."""
        return "rayleigh" if self.rayleigh is not None else "modal"


def _coefficient(ld: Loader, key: str, text, allowed, env: dict, index_range=None) -> Expr:
    """A whitelisted expression whose value is finite and ≥ 0 (at every index of a chain)."""
    expr = ld.expression(key, text, allowed, env=env, index_range=index_range)
    chunk = None if index_range is None else np.asarray(index_range, dtype=float)
    try:
        value = np.asarray(expr.evaluate(env if chunk is None else {**env, "i": chunk}), dtype=float)
    except (OverflowError, ZeroDivisionError, ValueError, TypeError, FloatingPointError):
        value = np.asarray(math.nan)
    if np.any(value < 0):
        first = float(value.ravel()[np.argmax(value.ravel() < 0)])
        raise ld.bad(key, text, f"evaluates to {first:g} (negative damping adds energy)",
                     "a value >= 0 at the scene's parameter values")
    if np.any(value > MAX_MAGNITUDE):
        raise ld.bad(key, text, f"evaluates to {float(np.max(value)):g}", f"values up to {MAX_MAGNITUDE:g}")
    return expr


def parse_damping(ld: Loader, pnames: frozenset[str], env: dict, n: int,
                  chain: bool = False) -> DampingModel | None:
    """The scene's ``[damping]`` table, or None without one.

    Parameters
    ----------
    ld : Loader
    pnames : frozenset of str
        Parameter names an expression may use.
    env : dict
        Parameter values.
    n : int
        Number of masses (= number of modes).
    chain : bool
        A ``[chain]`` scene: a modal list is refused (one ratio for every mode only).
    """
    if "damping" not in ld.data:
        return None
    table = ld.table("damping", example=" with rayleigh = [ALPHA, BETA] or modal = ZETA")
    ld.keys(table, DAMPING_KEYS, "damping", what="[damping]")
    if len(table) != 1:
        shown = "both rayleigh and modal" if table else "neither rayleigh nor modal"
        raise ld.bad("damping", shown, "give exactly one damping model", _FORM)
    if "rayleigh" in table:
        raw = table["rayleigh"]
        if not isinstance(raw, list) or len(raw) != 2:
            raise ld.bad("damping.rayleigh", raw, "not a list of two coefficients",
                         'rayleigh = [ALPHA, BETA] (C = ALPHA*M + BETA*K), numbers or expressions, e.g. [0.1, "2e-3"]')
        alpha, beta = (_coefficient(ld, f"damping.rayleigh[{j}]", v, pnames, env) for j, v in enumerate(raw))
        if all(float(np.max(np.abs(e.evaluate(env)))) == 0.0 for e in (alpha, beta)):
            raise ld.bad("damping.rayleigh", raw, "both coefficients are 0 (no damping)",
                         "at least one coefficient > 0, or leave [damping] out")
        return DampingModel(rayleigh=(alpha, beta))
    raw = table["modal"]
    if isinstance(raw, list):
        if chain:
            raise ld.bad("damping.modal", f"a list of {len(raw)} ratios", "a [chain] scene takes one ratio",
                         "modal = ZETA (the same ratio for every mode)")
        if len(raw) != n:
            raise ld.bad("damping.modal", raw, f"{len(raw)} ratios for {n} modes",
                         f"modal = ZETA or a list of exactly {n} ratios (one per mode, ascending omega)")
        ratios = tuple(_coefficient(ld, f"damping.modal[{j}]", v, pnames, env) for j, v in enumerate(raw))
    else:
        ratios = (_coefficient(ld, "damping.modal", raw, pnames, env),)
    if all(float(e.evaluate(env)) == 0.0 for e in ratios):
        raise ld.bad("damping.modal", raw, "every ratio is 0 (no damping)",
                     "at least one ratio > 0, or leave [damping] out")
    return DampingModel(modal=ratios)


__all__ = ["DampingModel", "DAMPING_KEYS", "parse_damping"]
