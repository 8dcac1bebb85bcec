"""Plans and benchmarks measured against an exact reference, for scenes the closed-form error
models do not cover: damped, forced, gravity and ground scenes (the augmented matrix
exponential of :mod:`numeric.exact.linear` is exact for them) and ``[chain]`` scenes above
:data:`numeric.plan.planner.MAX_MASSES` masses whose exact solution is the chain transform
(:mod:`numeric.exact.chain`, uniform chains). Nonlinear scenes of springs only (cubic springs,
spring potentials) up to MAX_MASSES masses have no exact solution: they are measured against a
tight DOP853 reference (rtol :data:`TIGHT_RTOL`) instead, and the exact method is no candidate.

Why not the closed-form models: :class:`~numeric.plan.error_models.LinearChainModel` describes an
undamped, unforced chain, and with damping the splitting of :mod:`numeric.run.effects` caps every
method at order 2; for long chains the model's dense modes do not fit in memory. So each step
method is **calibrated by two pilot runs** (steps h₁ = ½·limit/ω_max snapped to the reference
grid, and h₂ = h₁/2) over the horizon (or the longest pilot horizon within a work budget,
the error then taken ∝ T beyond it) against the exact reference:

    e(h) = C·h^p,  p = min(declared order, measured slope) (≥ 1),  C = max(e₁/h₁^p, e₂/h₂^p),

plus the rounding floor; the planned step never exceeds h₁ (the largest step measured).
Adaptive methods use the pilot-calibrated power law of :func:`numeric.plan.planner.calibrate_adaptive`
against the same reference. The ``model`` column says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .error_models import EPS, roundoff_floor
from ..errors import RunRefused
from .planner import MAX_MASSES, SAFETY, AdaptiveLaw, Candidate, Horizon, Plan, calibrate_adaptive, exact_method, \
    adaptive_atol, measure_exact_cost, measure_step_cost
from ..run import registry
from ..run.exact import Solution, solve
from ..run.grid import Grid
from ..run.protocol import Kind, Method, Options
from ..run.protocol import record
from ..system import System

#: Largest ``steps × N`` of one pilot run (the pilot horizon is shortened beyond it).
PILOT_WORK = 4e7
#: Most pilot runs per method (h halved each time until the measured slope reaches the order).
MAX_PILOT_LEVELS = 5
#: Largest ``frames × N`` of the reference kept in memory (the reference grid is coarsened beyond it).
REFERENCE_FLOATS = 4e6
#: Relative tolerance of the reference of nonlinear scenes (its own error is ~1e-12 of the state's size).
TIGHT_RTOL = 1e-13


def needs_pilot(system: System) -> bool:
    """Whether plan/bench take this route: not springs only, or a chain above MAX_MASSES."""
    return (not system.springs_only) or system.n > MAX_MASSES


def check_pilot(system: System, what: str) -> None:
    """Refuse (RunRefused, one line) a scene without an exact reference to measure against."""
    if system.springs_only and system.n > MAX_MASSES and not (system.chain and system.linear and system.uniform):
        raise RunRefused(f"{what} on a chain of more than {MAX_MASSES} masses needs its exact solution: "
                         f"a uniform linear [chain] (this one has {system.n} masses and is "
                         f"{'nonlinear' if not system.linear else 'index-dependent'})")
    why = system.no_exact_solution
    if why and not tight_reference_applies(system):
        drivers = [word for word, on in (("dampers", system.damped),
                                         ("forces", system.has("external_acceleration") or system.tabulated),
                                         ("ground motion", system.ground is not None),
                                         ("gravity", "gravity" in system.effects)) if on]
        raise RunRefused(f"{what}: this scene's {' and '.join(drivers)} put it outside the closed-form error models, "
                         f"so {what} calibrates every method by pilot runs against the exact solution, and there is "
                         f"none: {why}; accepted: linear springs with forces and ground acceleration constant + "
                         "harmonic (or tables), or a scene without dampers, forces, gravity and ground motion (cubic "
                         "springs and spring potentials are then planned against a tight DOP853 reference); compare "
                         "methods here with `springchain simulate --method NAME`")


def tight_reference_applies(system: System) -> bool:
    """A nonlinear scene of springs only and at most MAX_MASSES masses: no exact solution, so plan
    measures against a tight DOP853 reference (:data:`TIGHT_RTOL`) instead."""
    return system.springs_only and not system.linear and system.n <= MAX_MASSES


def tight_solution(system: System, x0: np.ndarray, v0: np.ndarray) -> Solution:
    """The registry's reference adaptive method (DOP853) at rtol :data:`TIGHT_RTOL`, as a
    :class:`~numeric.run.exact.Solution` on uniform grids ``t = k·h``."""
    atol = adaptive_atol(x0, v0, TIGHT_RTOL * 1e-2)  # far below rtol: the reference's error is relative
    method = registry.method(registry.REFERENCE_ADAPTIVE, Options(TIGHT_RTOL, atol, progress=False))

    def evaluate(t):
        h = float(t[1] - t[0]) if t.shape[0] > 1 else max(float(t[0]), 1.0)
        run = record(method, system, x0, v0, Grid(h, t.shape[0] - 1))
        return run.x, run.v

    return Solution(f"reference: {registry.REFERENCE_ADAPTIVE} at rtol {TIGHT_RTOL:g} (no exact solution: "
                    "nonlinear springs), float64", evaluate, whole=True)


class ExactReference:
    """The exact solution (:func:`numeric.run.exact.solve`) at the times of a uniform grid:
    ``at(t) -> (x, v)``, shapes (S, N), cached for the last grid asked.

    For a nonlinear scene of springs only (no exact solution) the reference is DOP853 at rtol
    :data:`TIGHT_RTOL` instead (:func:`tight_solution`), and ``exact`` is False.
    """

    def __init__(self, system: System, x0: np.ndarray, v0: np.ndarray):
        self.exact = not tight_reference_applies(system)
        self.solution: Solution = solve(system, x0, v0) if self.exact else tight_solution(system, x0, v0)
        self.description = self.solution.description
        self._cache: dict = {}

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x, v at the uniform grid ``t`` (one grid kept at a time: bounded memory)."""
        t = np.asarray(t, dtype=float)
        key = (t.shape[0], float(t[0]), float(t[-1]))
        if key not in self._cache:
            self._cache = {key: self.solution.at(t)}
        return self._cache[key]


def reference_grid(t_end: float, dt_out: float, n: int) -> Grid:
    """The reference grid ``t = k·spacing`` (spacing a multiple of ``dt_out``), at most
    ``REFERENCE_FLOATS / n`` frames."""
    k = max(1, math.ceil((t_end / dt_out) * n / REFERENCE_FLOATS))
    spacing = dt_out * k
    return Grid.frames_of(spacing, int(math.floor(t_end / spacing + 1e-9)) + 1)


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
    against: str = "the exact solution"

    def error(self, h: float, t_end: float) -> float:
        steps = t_end / h
        return self.C * h**self.p * max(1.0, t_end / self.t_pilot) + roundoff_floor(self.size, self.stages, steps)

    @property
    def label(self) -> str:
        grow = "" if math.isinf(self.t_pilot) else f", error ∝ T beyond t = {self.t_pilot:g}"
        runs = ", ".join(f"h = {h:.3g}: {e:.2g}" for h, e in self.pilots[-2:])
        return f"pilot-calibrated C·h^{self.p:.2g} against {self.against} ({runs}{grow})"


def _pilot_law(system: System, method: Method, ref: ExactReference, x0, v0, t_end: float, dt_out: float) -> PilotLaw:
    n, traits, w_max = system.n, method.traits, system.omega_max
    limit = traits.stability_limit if math.isfinite(traits.stability_limit) else 4.0
    h1_target = 0.5 * limit / max(w_max, 1e-300)
    steps_guess = 2 * t_end / h1_target * max(traits.evals_per_step, 1.0)
    t_pilot = t_end if steps_guess * n <= PILOT_WORK else max(dt_out, t_end * PILOT_WORK / (steps_guess * n))
    grid = reference_grid(t_pilot, dt_out, n)
    t_pilot = grid.t_end
    x_ref, _ = ref.at(grid.t)
    size = float(np.max(np.abs(x_ref)))
    j, m = _snap(h1_target, grid.h)
    stages = max(traits.evals_per_step, 1.0)
    order = float(traits.order)
    pilots: list[tuple[float, float]] = []
    p = order
    for level in range(MAX_PILOT_LEVELS):  # halve h until the measured slope reaches the order
        mm = m * 2**level
        h = grid.h * j / mm
        steps = (grid.steps // j) * mm
        if level >= 2 and steps * n * stages > 4 * PILOT_WORK:
            break
        try:
            tr = record(method, system, x0, v0, Grid(h, steps, mm))
        except RunRefused as exc:  # an implicit step's Newton iterations at the first, largest step: try h/2
            if pilots or getattr(exc, "quantity", None) != "dt":
                raise
            continue
        err = max(float(np.max(np.abs(tr.x - x_ref[::j][: tr.x.shape[0]]))), 1e-300)
        pilots.append((h, err))
        if len(pilots) == 1:
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
                    tuple(pilots), _against(ref.exact))


def _against(exact: bool) -> str:
    return "the exact solution" if exact else f"{registry.REFERENCE_ADAPTIVE} at rtol {TIGHT_RTOL:g}"


@dataclass(frozen=True)
class PilotPlanner(Horizon):
    """Plans for scenes measured against an exact reference (see the module docstring).

    ``laws``, ``step_costs`` and ``adaptive`` are keyed by the :class:`~numeric.run.protocol.Method`.
    """

    omega_max: float
    laws: dict = field(repr=False)
    step_costs: dict = field(repr=False)
    adaptive: dict = field(default_factory=dict, repr=False)
    exact_seconds: float = math.nan
    exact_error: float = math.nan
    reference: str = ""
    #: Whether the reference is the exact solution (then it is a candidate too); False for nonlinear scenes.
    exact: bool = True

    @classmethod
    def for_system(cls, system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float,
                   adaptive: bool = True, methods: tuple[str, ...] | None = None,
                   settings: tuple = ()) -> "PilotPlanner":
        """Pilot runs and costs of every method (``settings``: method settings such as HHT's alpha)."""
        check_pilot(system, "plan")
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        ref = ExactReference(system, x0, v0)
        w_max = system.omega_max
        laws, costs = {}, {}
        quiet = Options(progress=False, settings=settings)
        for m in registry.methods(Kind.STEP, quiet, only=methods):
            if not math.isfinite(m.traits.order) or m.refusal(system):
                continue  # the propagators (expm, chebyshev) integrate springs only
            laws[m] = _pilot_law(system, m, ref, x0, v0, t_end, dt_out)
            h_probe = min(dt_out, 0.5 * m.traits.stability_limit / max(w_max, 1e-300))
            short, long = (32, 288) if system.n <= MAX_MASSES else (2, max(4, min(288, int(PILOT_WORK // (8 * system.n)))))
            costs[m] = measure_step_cost(m, system, x0, v0, h_probe, short, long)
        # the exact method: its cost on the output grid (timed on a sample of it), rounding-level error
        out = reference_grid(t_end, dt_out, 1)
        sample = min(out.frames, max(2, int(REFERENCE_FLOATS // max(system.n, 1))), 2001)
        exact_seconds = measure_exact_cost(system, x0, v0, out, sample, budget=0.1) if ref.exact else math.nan
        size = max([law.size for law in laws.values()] + [float(np.max(np.abs(x0))), 1e-300])
        exact_error = EPS * size * (8.0 + w_max * t_end + math.sqrt(out.frames))
        laws_a = {}
        if adaptive:
            t_ad = t_end if system.n <= MAX_MASSES else min([t_end] + [law.t_pilot for law in laws.values()])
            g = reference_grid(t_ad, dt_out, system.n)

            def reference(t):
                return ref.at(t)[0]

            for m in registry.planned(Kind.ADAPTIVE, quiet, only=methods):
                if m.refusal(system) is None:
                    laws_a[m] = calibrate_adaptive(m, system, x0, v0, g.t_end, g.h, reference, scale=size)
        return cls(float(t_end), float(dt_out), system.n, w_max, laws, costs, laws_a, exact_seconds,
                   exact_error, ref.description, ref.exact)

    def plan_step(self, method: Method, tol: float) -> Candidate:
        law, cost = self.laws[method], self.step_costs[method]
        target = SAFETY * tol
        grow = max(1.0, self.t_end / law.t_pilot)
        h = (target / max(law.C * grow, 1e-300)) ** (1.0 / law.p) if law.C > 0 else law.h_max
        h = min(h, law.h_max)
        steps = max(1, math.ceil(self.t_end / h * (1 - 1e-12)))
        h = self.t_end / steps
        e = law.error(h, self.t_end)
        ok = e <= tol
        return Candidate(method, h, steps, None, e, cost(steps), ok,
                         law.label if ok else "rounding floor above the tolerance")

    def plan_adaptive(self, method: Method, tol: float) -> Candidate:
        from .planner import MIN_RTOL

        law: AdaptiveLaw = self.adaptive[method]
        rtol = law.error.solve(SAFETY * tol, self.t_end)
        ok = rtol >= MIN_RTOL
        rtol = max(min(rtol, 1e-2), MIN_RTOL)
        evals = law.evals(rtol, self.t_end)
        return Candidate(method, None, None, rtol, law.error(rtol, self.t_end),
                         evals * law.seconds_per_eval, ok, f"pilot-calibrated power law in rtol against {_against(self.exact)}")

    def plan(self, tol: float) -> Plan:
        if not (math.isfinite(tol) and tol > 0):
            raise ValueError(f"tolerance must be finite and > 0, got {tol!r}")
        cands = [Candidate(exact_method(), None, None, None, self.exact_error, self.exact_seconds,
                           self.exact_error <= tol, f"exact ({self.reference.split(': ', 1)[1]}); "
                           "error at the rounding level")] if self.exact else []
        cands += [self.plan_step(m, tol) for m in self.laws]
        cands += [self.plan_adaptive(m, tol) for m in self.adaptive]
        ok = tuple(c for c in cands if c.reachable)
        bad = tuple(c for c in cands if not c.reachable)
        if not ok:
            raise ValueError(f"no method reaches tol = {tol:g} over t = {self.t_end:g}: the rounding floors "
                             f"are above it (smallest predicted: {min(c.predicted_error for c in cands):.2g})")
        return Plan(tol, self.t_end, min(ok, key=lambda c: c.predicted_seconds), ok, bad)


__all__ = ["PilotPlanner", "PilotLaw", "ExactReference", "needs_pilot", "check_pilot", "REFERENCE_FLOATS",
           "TIGHT_RTOL", "tight_reference_applies", "tight_solution"]
