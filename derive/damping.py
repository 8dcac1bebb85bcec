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

DAMPING_KEYS = ("rayleigh", "modal", "rayleigh_targets")
_FORM = ("exactly one of rayleigh = [ALPHA, BETA], rayleigh_targets = {zeta = [ZETA_A, ZETA_B], modes = [A, B]}, "
         "modal = ZETA or modal = [ZETA_1, ..., ZETA_N]")
_TARGETS_FORM = ("rayleigh_targets = {zeta = [ZETA_A, ZETA_B], modes = [A, B]}: two damping ratios (numbers or "
                 "expressions >= 0, not both 0) at two different elastic modes counted from 1 in ascending omega")


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
    #: ``((ζ_a, ζ_b), (a, b))`` of ``rayleigh_targets``: Rayleigh damping meeting ζ_a, ζ_b at elastic
    #: modes a, b (from 1, ascending ω); α, β follow from the modes (:mod:`derive.rayleigh_targets`).
    targets: tuple[tuple[Expr, Expr], tuple[int, int]] | None = None

    @property
    def kind(self) -> str:
        """``"rayleigh"`` (given or from targets) or ``"modal"``."""
        return "rayleigh" if self.rayleigh is not None or self.targets is not None else "modal"


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
                  chain: bool = False, elastic: int | None = None) -> DampingModel | None:
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
    elastic : int, optional
        Number of elastic modes (``rayleigh_targets`` counts them); default ``n``.
    """
    if "damping" not in ld.data:
        return None
    table = ld.table("damping", example=" with rayleigh = [ALPHA, BETA] or modal = ZETA")
    ld.keys(table, DAMPING_KEYS, "damping", what="[damping]")
    if len(table) != 1:
        shown = " and ".join(sorted(table)) if table else "none of " + ", ".join(DAMPING_KEYS)
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
    if "rayleigh_targets" in table:
        return _targets(ld, table["rayleigh_targets"], pnames, env, chain, n if elastic is None else elastic)
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


def _targets(ld: Loader, raw, pnames, env, chain: bool, elastic: int) -> DampingModel:
    key = "damping.rayleigh_targets"
    if chain:
        raise ld.bad(key, raw, "Rayleigh targets on a [chain] are not yet supported",
                     "rayleigh = [ALPHA, BETA] on a [chain] (e.g. from the family zeta_j = alpha/(2 omega_j) + "
                     "beta omega_j/2); rayleigh_targets with [masses]")
    if not isinstance(raw, dict):
        raise ld.bad(key, raw, "not a table", _TARGETS_FORM)
    ld.keys(raw, ("zeta", "modes"), key, required=("zeta", "modes"), what="rayleigh_targets")
    zeta, modes = raw["zeta"], raw["modes"]
    if not isinstance(zeta, list) or len(zeta) != 2:
        raise ld.bad(f"{key}.zeta", zeta, "not a list of two damping ratios", _TARGETS_FORM)
    ratios = tuple(_coefficient(ld, f"{key}.zeta[{j}]", v, pnames, env) for j, v in enumerate(zeta))
    if all(float(e.evaluate(env)) == 0.0 for e in ratios):
        raise ld.bad(f"{key}.zeta", zeta, "both ratios are 0 (no damping)", _TARGETS_FORM)
    if any(float(e.evaluate(env)) >= 1.0 for e in ratios):
        raise ld.bad(f"{key}.zeta", zeta, "a ratio >= 1 (critical damping or more)", _TARGETS_FORM)
    if (not isinstance(modes, list) or len(modes) != 2
            or not all(isinstance(m, int) and not isinstance(m, bool) for m in modes)):
        raise ld.bad(f"{key}.modes", modes, "not a list of two mode numbers", _TARGETS_FORM)
    if modes[0] == modes[1] or not all(1 <= m <= elastic for m in modes):
        why = "the same mode twice" if modes[0] == modes[1] else f"the scene has {elastic} elastic modes"
        raise ld.bad(f"{key}.modes", modes, why, f"two different mode numbers 1 ... {elastic} (ascending omega, "
                                                 "rigid-body modes not counted)")
    return DampingModel(targets=(ratios, (modes[0], modes[1])))


__all__ = ["DampingModel", "DAMPING_KEYS", "parse_damping"]
