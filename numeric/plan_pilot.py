"""Plans and benchmarks measured against an exact reference, for scenes the closed-form error
models do not cover: damped, forced, gravity and ground scenes (the augmented matrix
exponential of :mod:`numeric.linear_exact` is exact for them) and ``[chain]`` scenes above
:data:`numeric.plan.MAX_MASSES` masses whose exact solution is the chain transform
(:mod:`numeric.chain_modal`, uniform chains).

Why not the closed-form models: :class:`~numeric.error_models.LinearChainModel` describes an
undamped, unforced chain, and with damping the splitting of :mod:`numeric.effects` caps every
method at order 2; for long chains the model's dense modes do not fit in memory. So each step
method is **calibrated by two pilot runs** (steps h₁ = ½·limit/ω_max snapped to the reference
grid, and h₂ = h₁/2) over the horizon (or the longest pilot horizon within a work budget,
the error then taken ∝ T beyond it) against the exact reference:

    e(h) = C·h^p,  p = min(declared order, measured slope) (≥ 1),  C = max(e₁/h₁^p, e₂/h₂^p),

plus the rounding floor; the planned step never exceeds h₁ (the largest step measured).
Adaptive methods use the pilot-calibrated power law of :func:`numeric.plan.calibrate_adaptive`
against the same reference. The ``model`` column says so.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .bounds import omega2_bound
from .driver import integrate
from .error_models import EPS, roundoff_floor
from .errors import RunRefused
from .integrators import ADAPTIVE, INTEGRATORS
from .integrators.base import Integrator, Problem
from .plan import MAX_MASSES, SAFETY, AdaptiveLaw, Candidate, ExactModal, Plan, StepCost, adaptive_atol, \
    calibrate_adaptive, measure_step_cost
from .system import LOADED_CHAIN_EXACT_MAX, System
from .timing import measure

#: Largest ``steps × N`` of one pilot run (the pilot horizon is shortened beyond it).
PILOT_WORK = 4e7
#: Most pilot runs per method (h halved each time until the measured slope reaches the order).
MAX_PILOT_LEVELS = 5
#: Largest ``frames × N`` of the reference kept in memory (the reference grid is coarsened beyond it).
REFERENCE_FLOATS = 4e6


def needs_pilot(system: System) -> bool:
    """Whether plan/bench take this route: not conservative, or a chain above MAX_MASSES."""
    return (not system.conservative) or system.n > MAX_MASSES


def check_pilot(system: System, what: str) -> None:
    """Refuse (RunRefused, one line) a scene without an exact reference to measure against."""
    if system.conservative and system.n > MAX_MASSES:
        if not (system.chain and system.linear and getattr(system.module, "UNIFORM", False)):
            raise RunRefused(f"{what} on a chain of more than {MAX_MASSES} masses needs its exact solution: "
                             f"a uniform linear [chain] (this one has {system.n} masses and is "
                             f"{'nonlinear' if not system.linear else 'index-dependent'})")
        return
    if not system.exact_available:
        mod = system.module
        drivers = [word for word, on in (("dampers", system.damped),
                                         ("forces", hasattr(mod, "external_acceleration") or system.tabulated),
                                         ("ground motion", system.ground is not None),
                                         ("gravity", "gravity" in system.effects)) if on]
        lacks = ("with cubic springs there is none" if not system.linear else
                 f"a loaded [chain] of more than {LOADED_CHAIN_EXACT_MAX} masses has none (it is dense)" if system.chain
                 else "forces or ground accelerations that are not constant + harmonic in t have none")
        raise RunRefused(f"{what}: this scene's {' and '.join(drivers)} put it outside the closed-form error models, "
                         f"so {what} calibrates every method by pilot runs against the exact solution, and {lacks}; "
                         "accepted: linear springs with forces and ground acceleration constant + harmonic (or "
                         "tables), or a scene without dampers, forces, gravity and ground motion (cubic springs "
                         "are then planned from their linearization); compare methods here with `springchain "
                         "simulate --method NAME`")


class ExactReference:
    """The exact solution at the times of a uniform grid: ``at(t) -> (x, v)``, shapes (S, N)."""

    def __init__(self, system: System, x0: np.ndarray, v0: np.ndarray):
        self.system, self.x0, self.v0 = system, np.asarray(x0, dtype=float), np.asarray(v0, dtype=float)
        if system.conservative:
            from .chain_modal import ChainModal

            self._chain = ChainModal.from_module(system.module, system.params, self.x0, self.v0)
            self.description = "exact: the chain's transform solution (numeric.chain_modal), float64"
        else:
            from .linear_exact import AugmentedLinear

            self._aug = AugmentedLinear.from_system(system)
            self.description = "exact: augmented matrix exponential (numeric.linear_exact), float64"
        self._cache: dict = {}

    def compute(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x, v at the uniform grid ``t``, computed afresh (what the exact method costs)."""
        t = np.asarray(t, dtype=float)
        if self.system.conservative:
            x, v = self._chain.at(t)
        else:
            x, v = self._aug.solve(self.x0, self.v0, t, float(t[1] - t[0]) if t.shape[0] > 1 else None)
        return np.asarray(x), np.asarray(v)

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`compute`, cached for the last grid asked (one grid at a time: bounded memory)."""
        t = np.asarray(t, dtype=float)
        key = (t.shape[0], float(t[0]), float(t[-1]))
        if key not in self._cache:
            self._cache = {key: self.compute(t)}
        return self._cache[key]


def adaptive_applies(name: str, system: System) -> bool:
    """Whether an adaptive method takes part in pilot plans and benches of ``system``: LSODA keeps
    a dense N × N Jacobian (left out above MAX_MASSES masses); the Runge–Kutta–Nyström pairs
    integrate x'' = f(t, x) and so leave out damped scenes."""
    if name == "lsoda" and system.n > MAX_MASSES:
        return False
    return ADAPTIVE[name].supports_damping or not system.damped


def wrapped(system: System, integ: Integrator) -> Integrator:
    """The integrator as runs use it: damping/forcing splitting around it where the scene needs it
    (the implicit Newmark/HHT steps integrate damping and loads themselves)."""
    if getattr(integ, "implicit", False):
        return type(integ).for_system(system)
    if system.damped or system.forced:
        from .effects import EffectSplitting

        return EffectSplitting(integ, system.damping_rate_matrix(), system.external_fn)
    return integ


def full_problem(system: System) -> Problem:
    """The first-order problem adaptive methods integrate (damping and forcing included)."""
    Ad = system.damping_rate_matrix()
    return Problem(system.acceleration_fn, damping=None if Ad is None else (lambda v: Ad @ v),
                   external=system.external_fn)


def omega_max(system: System) -> float:
    """ω_max: from the accurate spectrum (dense scenes) or the chain's closed form / a bound."""
    if system.n <= MAX_MASSES:
        from .spectrum import spectrum

        spec = spectrum(system.masses, system.spring_ends, system.stiffness)
        return float(spec.omega_max)
    mod = system.module
    if hasattr(mod, "mode_omega"):
        return float(np.max(mod.mode_omega(**system.params, n=system.n)))
    return math.sqrt(omega2_bound(system.masses, system.spring_ends, system.stiffness))


@dataclass(frozen=True)
class Grid:
    """The reference grid ``t = k·spacing``, k = 0 … frames − 1."""

    spacing: float
    frames: int

    @property
    def t(self) -> np.ndarray:
        return np.arange(self.frames) * self.spacing


def _grid(t_end: float, dt_out: float, n: int) -> Grid:
    k = max(1, math.ceil((t_end / dt_out) * n / REFERENCE_FLOATS))
    spacing = dt_out * k
    return Grid(spacing, int(math.floor(t_end / spacing + 1e-9)) + 1)


def _snap(h_target: float, spacing: float) -> tuple[int, int]:
    """``(j, m)`` with ``h = j·spacing/m`` ≤ h_target: every m-th step lies on the grid (every j-th point)."""
    if h_target >= spacing:
        return int(math.floor(h_target / spacing)), 1
    return 1, int(math.ceil(spacing / h_target))


@dataclass(frozen=True)
class PilotLaw:
    """``e(h, T) = C·h^p·max(1, T/t_pilot) + floor``, measured (see the module docstring)."""

    C: float
    p: float
    h_max: float
    t_pilot: float
    size: float
    stages: float
    pilots: tuple  # ((h, error), ...) of the pilot runs, h decreasing

    def error(self, h: float, t_end: float) -> float:
        steps = t_end / h
        return self.C * h**self.p * max(1.0, t_end / self.t_pilot) + roundoff_floor(self.size, self.stages, steps)

    @property
    def label(self) -> str:
        grow = "" if math.isinf(self.t_pilot) else f", error ∝ T beyond t = {self.t_pilot:g}"
        runs = ", ".join(f"h = {h:.3g}: {e:.2g}" for h, e in self.pilots[-2:])
        return f"pilot-calibrated C·h^{self.p:.2g} against the exact solution ({runs}{grow})"


def _pilot_law(system: System, integ: Integrator, problem: Problem, ref: ExactReference, x0, v0,
               t_end: float, dt_out: float, w_max: float) -> PilotLaw:
    n = system.n
    limit = integ.stability_limit if math.isfinite(integ.stability_limit) else 4.0
    h1_target = 0.5 * limit / max(w_max, 1e-300)
    steps_guess = 2 * t_end / h1_target * max(integ.evals_per_step, 1.0)
    t_pilot = t_end if steps_guess * n <= PILOT_WORK else max(dt_out, t_end * PILOT_WORK / (steps_guess * n))
    grid = _grid(t_pilot, dt_out, n)
    t_pilot = (grid.frames - 1) * grid.spacing
    x_ref, _ = ref.at(grid.t)
    size = float(np.max(np.abs(x_ref)))
    j, m = _snap(h1_target, grid.spacing)
    stages = max(integ.evals_per_step, 1.0)
    order = float(integ.order)
    pilots: list[tuple[float, float]] = []
    p = order
    for level in range(MAX_PILOT_LEVELS):  # halve h until the measured slope reaches the order
        mm = m * 2**level
        h = grid.spacing * j / mm
        steps = ((grid.frames - 1) // j) * mm
        if level >= 2 and steps * n * stages > 4 * PILOT_WORK:
            break
        tr = integrate(integ, problem, x0, v0, h, steps, record_every=mm)
        x = tr.x[:, :n, 0]
        err = max(float(np.max(np.abs(x - x_ref[::j][: x.shape[0]]))), 1e-300)
        pilots.append((h, err))
        if level == 0:
            continue
        (ha, ea), (hb, eb) = pilots[-2], pilots[-1]
        if eb <= 10 * roundoff_floor(size, stages, steps):  # on the rounding floor: the slope says nothing
            pilots.pop()
            break
        p = min(order, max(math.log(ea / eb) / math.log(ha / hb), 1.0))
        if p >= order - 0.25:
            break
    if len(pilots) < 2:
        p = order
    # the largest constant over every measured step: conservative at all h <= h1
    C = max(e / hh**p for hh, e in pilots)
    h1 = pilots[0][0]
    return PilotLaw(C, p, h1, t_pilot if t_pilot < t_end * (1 - 1e-9) else math.inf, size, stages,
                    tuple(pilots))


@dataclass(frozen=True)
class PilotPlanner:
    """Plans for scenes measured against an exact reference (see the module docstring)."""

    t_end: float
    dt_out: float
    n: int
    omega_max: float
    laws: dict = field(repr=False)
    integrators: dict = field(repr=False)
    step_costs: dict = field(repr=False)
    adaptive: dict = field(default_factory=dict, repr=False)
    exact_seconds: float = math.nan
    exact_error: float = math.nan
    reference: str = ""

    @classmethod
    def for_system(cls, system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float,
                   adaptive: bool = True, methods: tuple[str, ...] | None = None) -> "PilotPlanner":
        check_pilot(system, "plan")
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        ref = ExactReference(system, x0, v0)
        w_max = omega_max(system)
        problem = Problem.from_system(system)
        laws, integs, costs = {}, {}, {}
        for name, cls_ in INTEGRATORS.items():
            integ = cls_()
            if not math.isfinite(integ.order) or (methods and name not in methods):
                continue  # the propagators (expm, chebyshev) integrate springs only
            integ = wrapped(system, integ)
            integs[name] = integ
            laws[name] = _pilot_law(system, integ, problem, ref, x0, v0, t_end, dt_out, w_max)
            h_probe = min(dt_out, 0.5 * integ.stability_limit / max(w_max, 1e-300))
            short, long = (32, 288) if system.n <= MAX_MASSES else (2, max(4, min(288, int(PILOT_WORK // (8 * system.n)))))
            costs[name] = measure_step_cost(wrapped(system, cls_()), problem, x0, v0, h_probe, short, long)
        # the exact method: its cost on the output grid (timed on a sample of it), rounding-level error
        grid = _grid(t_end, dt_out, 1)
        sample = min(grid.frames, max(2, int(REFERENCE_FLOATS // max(system.n, 1))), 2001)
        probe = ExactReference(system, x0, v0)
        secs = measure(lambda: probe.compute(np.arange(sample) * grid.spacing), budget=0.1).seconds
        exact_seconds = secs * grid.frames / sample
        size = max([law.size for law in laws.values()] + [float(np.max(np.abs(x0))), 1e-300])
        exact_error = EPS * size * (8.0 + w_max * t_end + math.sqrt(grid.frames))
        laws_a = {}
        if adaptive:
            fp = full_problem(system)
            t_ad = t_end if system.n <= MAX_MASSES else min(
                [t_end] + [law.t_pilot for law in laws.values()])
            g = _grid(t_ad, dt_out, system.n)
            t_ad = (g.frames - 1) * g.spacing

            def reference(t):
                return ref.at(t)[0]

            for name, cls_ in ADAPTIVE.items():
                if (methods and name not in methods) or not adaptive_applies(name, system):
                    continue
                laws_a[name] = calibrate_adaptive(cls_(), fp, x0, v0, t_ad, g.spacing, reference, scale=size)
        return cls(float(t_end), float(dt_out), system.n, w_max, laws, integs, costs, laws_a, exact_seconds,
                   exact_error, ref.description)

    def plan_step(self, name: str, tol: float) -> Candidate:
        law, integ, cost = self.laws[name], self.integrators[name], self.step_costs[name]
        target = SAFETY * tol
        grow = max(1.0, self.t_end / law.t_pilot)
        h = (target / max(law.C * grow, 1e-300)) ** (1.0 / law.p) if law.C > 0 else law.h_max
        h = min(h, law.h_max)
        steps = max(1, math.ceil(self.t_end / h * (1 - 1e-12)))
        h = self.t_end / steps
        e = law.error(h, self.t_end)
        ok = e <= tol
        return Candidate(integ, h, steps, None, e, cost(steps), ok,
                         law.label if ok else "rounding floor above the tolerance")

    def plan_adaptive(self, name: str, tol: float) -> Candidate:
        from .plan import MIN_RTOL

        law: AdaptiveLaw = self.adaptive[name]
        rtol = law.error.solve(SAFETY * tol, self.t_end)
        ok = rtol >= MIN_RTOL
        rtol = max(min(rtol, 1e-2), MIN_RTOL)
        evals = law.evals(rtol, self.t_end)
        return Candidate(ADAPTIVE[name](), None, None, rtol, law.error(rtol, self.t_end),
                         evals * law.seconds_per_eval, ok, "pilot-calibrated power law in rtol against the exact solution")

    def plan(self, tol: float) -> Plan:
        if not (math.isfinite(tol) and tol > 0):
            raise ValueError(f"tolerance must be finite and > 0, got {tol!r}")
        cands = [Candidate(ExactModal(), None, None, None, self.exact_error, self.exact_seconds,
                           self.exact_error <= tol, f"exact ({self.reference.split(': ', 1)[1]}); "
                           "error at the rounding level")]
        cands += [self.plan_step(name, tol) for name in self.laws]
        cands += [self.plan_adaptive(name, tol) for name in self.adaptive]
        ok = tuple(c for c in cands if c.reachable)
        bad = tuple(c for c in cands if not c.reachable)
        if not ok:
            raise ValueError(f"no method reaches tol = {tol:g} over t = {self.t_end:g}: the rounding floors "
                             f"are above it (smallest predicted: {min(c.predicted_error for c in cands):.2g})")
        return Plan(tol, self.t_end, min(ok, key=lambda c: c.predicted_seconds), ok, bad)


__all__ = ["PilotPlanner", "PilotLaw", "ExactReference", "needs_pilot", "check_pilot", "wrapped", "full_problem",
           "adaptive_applies"]
