"""Least-squares model updating on analytic sensitivities, with honest uncertainties.

The unknowns are ``θ = log p`` of the fitted parameters (positive by construction; a relative change of
p is a unit of θ). The residuals are weighted so that each has unit variance when the noise is known:

* a frequency: ``(ω_j(θ) − ω̃_j) / σ_j`` (``σ_j`` = ``omega_std``), or, without standard deviations, the
  relative error ``(ω_j(θ) − ω̃_j) / ω̃_j`` with one noise level estimated from the fit;
* a shape at the sensors: the measured shape ψ (scaled to 1 in magnitude at its largest sensor) minus the
  multiple of the model's shape φ that fits it best, ``(ψ − α φ) / σ_s`` with the modal scale factor
  ``α = φᵀψ/φᵀφ`` — what the model cannot explain by a scale, free of any division by a noisy value.

Their Jacobian is exact: ``∂ω/∂θ = p (∂ω²/∂p) / (2ω)`` and the shape derivatives of Nelson's method
(:mod:`numeric.sensitivity`). SciPy's trust-region reflective ``least_squares`` minimises the sum of
squares (bounds on p become bounds on θ).

**Identifiability.** The singular values ``s_1 ≥ … ≥ s_P`` of the weighted Jacobian at the start say
what the data can fix: a direction ``v_i`` with ``s_i ≤ IDENTIFIABLE_RTOL · s_1`` changes no residual
(to first order) — e.g. two springs acting in parallel, or k and m together when only frequencies are
measured. Such a combination is named (``+0.707·log k1 − 0.707·log k2``), kept at its starting value
(the fit runs in the identifiable subspace ``θ = θ₀ + V z``) and its parameters get no standard error,
instead of a wild value along a flat valley.

**Uncertainty.** ``Cov(θ) = s² V Σ⁻² Vᵀ`` on the identifiable subspace, with ``s² = 1`` when the noise is
known and ``s² = RSS/(m − rank)`` otherwise; ``SE(p) = p·SE(θ)`` (first order), correlations from Cov(θ).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import RunRefused

#: Singular values below this fraction of the largest: directions the data do not fix.
IDENTIFIABLE_RTOL = 1e-8
#: A parameter belongs to an unidentifiable combination when its weight there exceeds this.
INVOLVED = 1e-3
#: Most model evaluations of one fit.
MAX_EVALUATIONS = 200
#: Why SciPy's ``least_squares`` stopped (its ``status``), in the report's words.
STOPPED = {0: f"stopped at the evaluation limit ({MAX_EVALUATIONS}) before converging",
           1: "converged (the gradient vanished to working precision)",
           2: "converged (the sum of squares stopped decreasing)",
           3: "converged (the parameter step fell below working precision)",
           4: "converged (the sum of squares and the parameter step both settled)"}


@dataclass(frozen=True)
class Problem:
    """A weighted least-squares problem in ``θ = log p``.

    Attributes
    ----------
    names : tuple of str
    start : ndarray, shape (P,)
        Starting parameter values (> 0).
    residual : callable
        ``residual(p) -> (r (m,), J (m, P))``: weighted residuals and their Jacobian with respect to θ.
    lower, upper : ndarray, shape (P,)
        Bounds on p (0 and inf when none).
    known_noise : bool
        Whether the weights are the measurement's standard deviations (else one noise level is estimated).
    constrained : int
        Residual directions that vanish whatever the parameters (one per shape: ψ − αφ ⟂ φ), taken off the
        degrees of freedom.
    """

    names: tuple[str, ...]
    start: np.ndarray
    residual: Callable
    lower: np.ndarray
    upper: np.ndarray
    known_noise: bool
    constrained: int = 0


class Memo:
    """``fn(x)`` evaluated once per point: SciPy's ``least_squares`` asks for the residual and then for the
    Jacobian at the same point, and each model evaluation yields both.

    Keeps the first point's value (the start, asked again for the report), the value of lowest ``score``
    (the trust-region method accepts a step only when the cost falls, so its solution is the evaluated
    point of lowest cost, asked again at the end) and the last ``keep`` others, keyed by the exact bits of
    ``x`` (a float array).

    Parameters
    ----------
    fn : callable
        ``fn(x (P,)) -> value``.
    score : callable, optional
        ``score(value) -> float``: the cost of a value.
    keep : int
    """

    def __init__(self, fn: Callable, score: Callable | None = None, keep: int = 2):
        self.fn, self.score, self.keep = fn, score, keep
        self.values: dict[bytes, object] = {}
        self.best: tuple[float, bytes] | None = None
        #: Evaluations of ``fn`` (points not found in the memo).
        self.calls = 0

    def __call__(self, x):
        key = np.ascontiguousarray(x, dtype=float).tobytes()
        if key in self.values:
            return self.values[key]
        self.calls += 1
        value = self.fn(x)
        if self.score is not None:
            cost = float(self.score(value))
            if self.best is None or cost < self.best[0]:
                self.best = (cost, key)
        pinned = {next(iter(self.values), None), self.best[1] if self.best else None}
        others = [k for k in self.values if k not in pinned]
        for k in others[:max(len(others) - self.keep + 1, 0)]:
            del self.values[k]
        self.values[key] = value
        return value


@dataclass(frozen=True)
class Fit:
    """The result of :func:`solve`.

    Attributes
    ----------
    values : ndarray, shape (P,)
    standard_errors : ndarray, shape (P,)
        NaN for parameters in an unidentifiable combination.
    correlations : ndarray, shape (P, P)
        NaN rows/columns for those parameters.
    covariance_log : ndarray, shape (P, P)
        Cov(log p).
    singular_values : ndarray, shape (P,)
        Of the weighted Jacobian at the start, descending.
    directions : ndarray, shape (P, P)
        The matching right singular vectors (columns), in log-parameter units.
    unidentifiable : list of ndarray
        Directions (P,) the data do not fix.
    identifiable : ndarray of bool, shape (P,)
    residual_start, residual_end : ndarray, shape (m,)
    noise_scale : float
        s (1 when the noise is known).
    chi2 : float
        Sum of squared weighted residuals at the end.
    dof : int
        Residuals minus identifiable parameters.
    status : str
    evaluations : int
        Model evaluations (each gives the residuals and their Jacobian at one point, once).
    """

    values: np.ndarray = field(repr=False)
    standard_errors: np.ndarray = field(repr=False)
    correlations: np.ndarray = field(repr=False)
    covariance_log: np.ndarray = field(repr=False)
    singular_values: np.ndarray = field(repr=False)
    directions: np.ndarray = field(repr=False)
    unidentifiable: list = field(repr=False)
    identifiable: np.ndarray = field(repr=False)
    residual_start: np.ndarray = field(repr=False)
    residual_end: np.ndarray = field(repr=False)
    noise_scale: float = 1.0
    chi2: float = 0.0
    dof: int = 0
    status: str = ""
    evaluations: int = 0
    #: With unidentifiable directions: the identifiable ones ``(v (P,), v·log p, its standard error)``.
    combinations: list = field(default_factory=list, repr=False)


def describe(direction: np.ndarray, names: tuple[str, ...]) -> str:
    """A combination of log-parameters as text: ``+0.707·log k1 − 0.707·log k2`` (sign: first term positive)."""
    v = np.asarray(direction, dtype=float)
    big = np.flatnonzero(np.abs(v) > INVOLVED * np.max(np.abs(v)))
    v = v * (1.0 if v[big[0]] > 0 else -1.0)
    return " ".join(f"{'+' if v[i] > 0 else '-'}{abs(v[i]):.3g}·log {names[i]}" for i in big)


def solve(problem: Problem) -> Fit:
    """Fit, then report values, standard errors, correlations and identifiability (module docstring).

    Raises
    ------
    RunRefused
        Fewer residuals than identifiable parameters with the noise unknown; residuals that are not finite
        at the start.
    """
    from scipy.optimize import least_squares

    P = len(problem.names)
    theta0 = np.log(problem.start)
    start_key = theta0.tobytes()
    # one model evaluation per point p (two θ an ulp apart may give one p); at θ₀ the given start itself, not
    # exp(log p), which may differ from it by an ulp
    memo = Memo(problem.residual, score=lambda rj: float(rj[0] @ rj[0]))

    def at(t):
        return memo(problem.start if t.tobytes() == start_key else np.exp(t))

    r0, J0 = at(theta0)
    if not (np.all(np.isfinite(r0)) and np.all(np.isfinite(J0))):
        raise RunRefused("update: the residuals or their Jacobian are not finite at the starting parameters")
    m = r0.shape[0] - problem.constrained
    _, s, vt = np.linalg.svd(J0, full_matrices=True)
    s = np.concatenate([s, np.zeros(P - s.shape[0])]) if s.shape[0] < P else s
    V = vt.T
    flat = s <= IDENTIFIABLE_RTOL * (s[0] if s.size and s[0] > 0 else 1.0)
    V_id, V_null = V[:, ~flat], V[:, flat]
    rank = int((~flat).sum())
    if not problem.known_noise and m <= rank:
        raise RunRefused(f"update: {m} residuals for {rank} identifiable parameters: the noise level is estimated "
                         "from the fit, which needs more residuals than parameters; accepted: more measured modes or "
                         "shapes, fewer parameters, or standard deviations in the file (omega_std)", "parameters")
    lo = np.log(np.maximum(problem.lower, 1e-300))
    hi = np.log(np.where(np.isfinite(problem.upper), problem.upper, np.inf))

    def fun(z):
        return at(theta0 + V_id @ z)[0].copy()  # SciPy owns what it is given

    def jac(z):
        return at(theta0 + V_id @ z)[1] @ V_id

    status = "no identifiable parameter"
    theta = theta0.copy()
    if rank:
        if V_null.shape[1] == 0:  # full rank: bounds apply directly (V_id is orthogonal)
            res = least_squares(lambda t: at(t)[0].copy(), np.clip(theta0, lo, hi), jac=lambda t: at(t)[1].copy(),
                                bounds=(lo, hi), method="trf", x_scale=1.0, ftol=1e-15, xtol=1e-15, gtol=1e-15,
                                max_nfev=MAX_EVALUATIONS)
            theta = res.x
        else:
            res = least_squares(fun, np.zeros(rank), jac=jac, method="trf", x_scale=1.0, ftol=1e-15, xtol=1e-15,
                                gtol=1e-15, max_nfev=MAX_EVALUATIONS)
            theta = theta0 + V_id @ res.x
        status = STOPPED.get(int(res.status), f"stopped (SciPy status {int(res.status)})")
    r1, J1 = at(theta)
    p_end = problem.start if theta.tobytes() == start_key else np.exp(theta)
    chi2 = float(np.sum(r1 * r1))
    dof = m - rank
    scale = 1.0 if problem.known_noise else float(np.sqrt(chi2 / dof)) if dof > 0 else np.nan
    # the covariance on the identifiable subspace, from the Jacobian at the solution
    Jr = J1 @ V_id
    G = Jr.T @ Jr
    try:
        cov_z = np.linalg.inv(G) if rank else np.zeros((0, 0))
    except np.linalg.LinAlgError:
        cov_z = np.linalg.pinv(G)
    cov = scale**2 * (V_id @ cov_z @ V_id.T)
    involved = np.any(np.abs(V_null) > INVOLVED, axis=1) if V_null.shape[1] else np.zeros(P, dtype=bool)
    se_log = np.sqrt(np.maximum(np.diag(cov), 0.0))
    se = np.where(involved, np.nan, p_end * se_log)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se_log, se_log)
    corr[involved, :] = np.nan
    corr[:, involved] = np.nan
    combos = []
    if V_null.shape[1]:
        for i in range(V_id.shape[1]):
            v = V_id[:, i] * (1.0 if V_id[np.argmax(np.abs(V_id[:, i])), i] > 0 else -1.0)
            combos.append((v, float(v @ theta), float(np.sqrt(max(v @ cov @ v, 0.0)))))
    return Fit(p_end, se, corr, cov, s, V, [V_null[:, i] for i in range(V_null.shape[1])], ~involved, r0, r1,
               scale, chi2, dof, str(status), memo.calls, combos)


__all__ = ["Problem", "Fit", "Memo", "solve", "describe", "IDENTIFIABLE_RTOL"]
