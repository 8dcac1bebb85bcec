"""The accuracy planner behind ``springchain plan``: the cheapest way to reach a tolerance.

*Error* means what the benchmark measures: the largest absolute position
error over all recorded times, with fixed-step methods recording every step
(``t = i·h``) and the exact, propagator and adaptive methods recording the
scene's output grid.

For each method the planner predicts the step (or tolerance) that just
reaches ``tol`` and the seconds that costs, then recommends the cheapest:

* step methods on a linear chain: :class:`~numeric.plan.error_models.LinearChainModel`
  evaluated exactly (closed-form numerical solution per mode) when that is
  cheap, else its envelope; plus the rounding floor. The planned step is
  the largest ``h = T/n`` whose prediction is at most :data:`SAFETY`·tol
  and that is stable (``ω_max·h`` below the method's limit, ``ω_max`` exact
  from the spectrum). A tolerance below a method's rounding floor is
  unreachable: the method is left out of the candidates and named in
  :attr:`Plan.unreachable`.
* step methods on a nonlinear scene: the same model on the linearization,
  scaled per method by measured/predicted on one short pilot run against a
  reference (DOP853 at rtol 1e-13, or the benchmark's reference).
* adaptive methods: a power law ``error = c·rtol^α·T/T_pilot`` and a cost law
  calibrated from two short pilot runs (:func:`calibrate_adaptive`).
* the exact modal solution, ``expm`` and ``chebyshev``: error at the
  rounding level; cost measured (the modal solution's eigen-decomposition
  and evaluation on the output grid are timed as one run).

Seconds are *measured* costs of this machine: seconds per step of each
method on this scene (timed through the same driver the runs use, minimum
of repeats, single-threaded BLAS) times the planned number of steps, plus
its measured set-up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..errors import RunRefused
from .error_models import EPS, LinearChainModel, OscillatorResponse, PowerLaw, roundoff_floor
from ..run import registry
from ..run.exact import solve
from ..run.grid import Grid
from ..run.protocol import Kind, Method, Options, SpectrumSource
from ..run.recorder import MemoryRecorder
from ..run.protocol import record
from ..system import System
from ..bench.timing import measure

#: Planned steps aim at this fraction of the tolerance (the exact-for-linear model is exact up to roundoff).
SAFETY = 0.7
#: The smallest relative tolerance passed to ``solve_ivp`` (SciPy warns below 100·ε).
MIN_RTOL = 3e-14
#: Pilot tolerances of the adaptive calibration.
PILOT_RTOLS = (1e-5, 1e-8)
#: Largest ``steps · N · M`` for which the exact closed-form error is evaluated (else: envelope).
EXACT_BUDGET = 1_000_000
#: Largest number of steps considered for a step method.
MAX_STEPS = 10**12
#: The planner and the benchmark work on the dense modes of the chain: small and moderate scenes only.
MAX_MASSES = 2000


#: ``atol = ATOL_FRACTION · rtol · scale``: the relative tolerance governs; atol only guards zero crossings
#: (a looser atol, e.g. rtol·scale, keeps DOP853 above 1e-12 on the seed scene even at its smallest rtol).
ATOL_FRACTION = 1e-3


def adaptive_atol(x0: np.ndarray, v0: np.ndarray, rtol: float, scale: float | None = None) -> float:
    """The absolute tolerance paired with ``rtol``: ``ATOL_FRACTION · rtol`` times the initial state's scale
    (or ``scale``, e.g. the size of a forced response that starts from rest)."""
    if scale is None:
        scale = max(float(np.max(np.abs(x0), initial=0.0)), float(np.max(np.abs(v0), initial=0.0)), 1e-300)
    return ATOL_FRACTION * rtol * scale


@dataclass(frozen=True)
class Candidate:
    """A method with the setting that reaches the tolerance, and its predicted cost.

    Attributes
    ----------
    method : Method
    dt : float or None
        Planned step ``T/n`` (None for methods without a step).
    steps : int or None
    rtol : float or None
        Planned relative tolerance of an adaptive method (``atol`` from :func:`adaptive_atol`).
    predicted_error, predicted_seconds : float
    reachable : bool
        False when the tolerance is below the method's rounding floor (or its tolerance range).
    model : str
        Which model made the prediction.
    """

    method: Method
    dt: float | None
    steps: int | None
    rtol: float | None
    predicted_error: float
    predicted_seconds: float
    reachable: bool = True
    model: str = ""

    @property
    def name(self) -> str:
        return self.method.name

    def as_json(self) -> dict:
        return {"method": self.name, "dt": self.dt, "predicted_error": float(self.predicted_error),
                "predicted_seconds": float(self.predicted_seconds)}


@dataclass(frozen=True)
class Plan:
    """The candidates that reach ``tol`` and the cheapest of them."""

    tol: float
    t_end: float
    recommended: Candidate
    candidates: tuple[Candidate, ...]
    unreachable: tuple[Candidate, ...] = ()

    def as_json(self) -> dict:
        return {"recommended": self.recommended.as_json(), "candidates": [c.as_json() for c in self.candidates]}

    def _repr_html_(self) -> str:  # a notebook shows the table ``springchain plan`` prints
        from ..plots.html import plan_table

        return plan_table(self)


@dataclass(frozen=True)
class StepCost:
    """Measured cost of a step method through the path its run takes: ``setup + per_step · steps`` seconds.

    On a small ``[masses]`` scene a run of at least ``compiled_from`` steps takes the compiled loop
    (:func:`numeric.compiled.run.route`); its cost is ``compiled()`` → ``(per_step, setup)``, measured on
    first need (a plan whose runs are all short compiles nothing) and kept.
    """

    per_step: float
    setup: float
    compiled: Callable[[], tuple[float, float]] | None = field(default=None, compare=False, repr=False)
    compiled_from: float = math.inf
    _measured: dict = field(default_factory=dict, compare=False, repr=False)

    def __call__(self, steps: int) -> float:
        if self.compiled is not None and steps >= self.compiled_from:
            if "compiled" not in self._measured:
                self._measured["compiled"] = self.compiled()
            per_step, setup = self._measured["compiled"]
            return setup + per_step * steps
        return self.setup + self.per_step * steps


@dataclass(frozen=True)
class AdaptiveLaw:
    """Pilot-calibrated error and cost of an adaptive method (see :class:`~numeric.plan.error_models.PowerLaw`)."""

    error: PowerLaw
    evals: PowerLaw
    seconds_per_eval: float


def _two_runs(method: Method, system: System, x0: np.ndarray, v0: np.ndarray, h: float, short: int, long: int,
              budget: float, compiled: bool = False) -> tuple[float, float]:
    """``(per_step, setup)`` from timed runs of ``short`` and ``long`` steps (``compiled``: after a warm-up
    run of two steps that compiles or loads the loop)."""
    warm = (lambda: record(method, system, x0, v0, Grid(h, 2))) if compiled else None  # compiles, untimed
    t_short = measure(lambda: record(method, system, x0, v0, Grid(h, short)), budget=budget, warmup=warm).seconds
    t_long = measure(lambda: record(method, system, x0, v0, Grid(h, long)), budget=budget, warmup=warm).seconds
    per_step = max((t_long - t_short) / (long - short), t_long / long * 0.5)
    return per_step, max(t_short - per_step * short, 0.0)


#: Steps of the two timed runs of a compiled loop (a step costs tens of ns there, not µs).
COMPILED_PROBE = (2_000, 20_000)


def measure_step_cost(method: Method, system: System, x0: np.ndarray, v0: np.ndarray, h: float,
                      short: int = 32, long: int = 288, budget: float = 0.05) -> StepCost:
    """Seconds per step and set-up of a step method on this system, from two timed runs of the NumPy
    driver; where long runs take a compiled loop, the loop's own cost too (measured on first need,
    compiled outside the timing: :class:`StepCost`)."""
    from ..compiled import run as compiled_run

    per_step, setup = _two_runs(method, system, x0, v0, h, short, long, budget)
    loop_of = getattr(method, "compiled_loop", None)
    if loop_of is None or np.ndim(x0) != 1:
        return StepCost(per_step, setup)
    with compiled_run.eager():
        loop = loop_of(system, method.integrator(system), Grid(h, long))
    if loop is None:
        return StepCost(per_step, setup)
    stages = max(method.traits.evals_per_step, 1.0)
    start = compiled_run.min_evals(system, loop) / stages

    def compiled() -> tuple[float, float]:
        with compiled_run.eager():  # the probes are short: take the loop (its warm-up call compiles it)
            return _two_runs(method, system, x0, v0, h, *COMPILED_PROBE, budget, compiled=True)

    return StepCost(per_step, setup, compiled, start)


def exact_method(source: SpectrumSource = SpectrumSource.SVD) -> Method:
    """The registered exact method, its modes from ``source``."""
    return registry.method(registry.EXACT, Options(spectrum=source, progress=False))


def measure_exact_cost(system: System, x0: np.ndarray, v0: np.ndarray, grid: Grid, sample: int,
                       budget: float) -> float:
    """Seconds of the exact method on ``grid``: its set-up (on a fresh system, so nothing it computes is
    cached) plus its evaluation on the first ``sample`` frames, scaled to the whole grid."""
    method = exact_method()
    setup = measure(lambda: method.prepare(system.fresh(), x0, v0), budget=budget)
    part = grid if sample >= grid.frames else Grid.frames_of(grid.h, sample)
    evaluate = measure(lambda: setup.result.record(part, MemoryRecorder(part.frames, system.n), system.n, False),
                       budget=budget).seconds
    return setup.seconds + evaluate * grid.frames / part.frames


def with_tolerance(method: Method, x0: np.ndarray, v0: np.ndarray, rtol: float, scale: float | None = None) -> Method:
    """An adaptive method at ``rtol`` with its paired absolute tolerance (:func:`adaptive_atol`)."""
    return method.with_options(Options(rtol, adaptive_atol(x0, v0, rtol, scale), progress=False))


def calibrate_adaptive(method: Method, system: System, x0: np.ndarray, v0: np.ndarray,
                       t_pilot: float, dt_out: float,
                       reference: Callable[[np.ndarray], np.ndarray], scale: float | None = None) -> AdaptiveLaw:
    """Two pilot runs (rtol 1e-5 and 1e-8) over ``t_pilot`` against ``reference(t) -> x (S, N)``
    (``scale``: the state scale of the absolute tolerance, see :func:`adaptive_atol`)."""
    grid = Grid.covering(t_pilot, dt_out)
    x_ref = reference(grid.t)
    errs, evals, secs = [], [], 0.0
    for rtol in PILOT_RTOLS:
        run = with_tolerance(method, x0, v0, rtol, scale)
        timing = measure(lambda run=run: record(run, system, x0, v0, grid), budget=0.0, max_repeats=1)
        res = timing.result
        errs.append(max(float(np.max(np.abs(res.x - x_ref))), 1e-300))
        evals.append(float(res.force_evals))
        secs += timing.seconds
    (r1, r2), (e1, e2), (n1, n2) = PILOT_RTOLS, errs, evals
    return AdaptiveLaw(PowerLaw.through(r1, e1, r2, e2, t_pilot, alpha_bounds=(0.3, 1.5)),
                       PowerLaw.through(r1, n1, r2, n2, t_pilot, alpha_bounds=(-1.0, 0.0)),
                       secs / (n1 + n2))


@dataclass(frozen=True)
class Horizon:
    """What a plan is for: errors over ``t = 0 … t_end`` on the output spacing ``dt_out``, ``n`` masses."""

    t_end: float
    dt_out: float
    n: int

    @property
    def output_grid(self) -> Grid:
        """The output times ``t = i·Δ`` over the horizon (Δ ≤ dt_out)."""
        return Grid.covering(self.t_end, self.dt_out)


@dataclass(frozen=True)
class Planner(Horizon):
    """Everything measured once for a scene, from which plans for any tolerance follow.

    Build with :meth:`for_system`; then :meth:`plan` (cheap) for each tolerance.

    Attributes
    ----------
    t_end, dt_out : float
        Horizon and output spacing.
    model : LinearChainModel
        Modes of the chain (of its linearization for a nonlinear scene).
    exact : bool
        Whether the scene has the exact modal solution (linear, undamped, unforced).
    step_methods : tuple of Method
        Finite-order step methods with their :class:`OscillatorResponse` in ``responses``.
    """

    model: LinearChainModel
    exact: bool
    step_methods: tuple
    responses: dict = field(repr=False)
    step_costs: dict = field(repr=False)
    propagators: tuple = ()
    adaptive: dict = field(default_factory=dict, repr=False)
    modal_seconds: float = math.nan
    #: Per-method factor measured/predicted from a pilot run (nonlinear scenes; empty otherwise).
    calibration: dict = field(default_factory=dict, repr=False)

    @classmethod
    def for_system(cls, system: System, x0: np.ndarray, v0: np.ndarray, t_end: float, dt_out: float,
                   adaptive: bool = True, reference: Callable | None = None, settings: tuple = (),
                   only: frozenset | None = None) -> "Planner":
        """Measure costs and build the models (call inside :func:`~numeric.bench.timing.single_threaded_blas`).

        Parameters
        ----------
        reference : callable, optional
            ``reference(t) -> x (S, N)`` at multiples ``t`` of ``dt_out``, for the pilot runs
            (adaptive methods; step methods on a nonlinear scene). Default: the exact modal
            solution (linear scenes) or DOP853 at rtol 1e-13 (others).
        settings : tuple of (str, float), optional
            Method settings (HHT's ``alpha``: :attr:`~numeric.run.protocol.Options.settings`), checked by the caller.
        only : frozenset of str, optional
            Names of the methods to measure and model (bench's selection); default every planned one.
        """
        if system.n > MAX_MASSES:
            raise RunRefused(f"plan and bench use the dense modes of the chain: at most {MAX_MASSES} masses "
                             f"(this scene has {system.n}); for long chains see `springchain scaling`")
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        spec = system.spectrum
        model = LinearChainModel.from_spectrum(spec, x0, v0)
        exact = bool(system.springs_only and system.exact_available)
        steps_, responses, costs, props = [], {}, {}, []
        h_probe = min(dt_out, 0.5 / max(model.omega_max, 1e-300))
        for m in registry.methods(Kind.STEP, Options(progress=False, settings=settings)):
            if (only is not None and m.name not in only) or m.refusal(system):
                continue
            if not math.isfinite(m.traits.order):
                if exact:
                    props.append(m)
                    costs[m] = measure_step_cost(m, system, x0, v0, Grid.covering(t_end, dt_out).h)
                continue
            steps_.append(m)
            responses[m] = m.response()
            costs[m] = measure_step_cost(m, system, x0, v0, h_probe)
        modal_seconds = math.nan
        grid = Grid.covering(t_end, dt_out)
        if exact:
            modal_seconds = measure_exact_cost(system, x0, v0, grid, grid.frames if grid.frames <= 200_001 else 20_001,
                                               budget=0.2)
        periods = 20 if exact else 5  # nonlinear pilots also need a reference run: keep them short
        t_pilot = min(t_end, periods * 2 * math.pi / float(model.omega.min())) if model.omega.size else t_end
        t_pilot = max(dt_out, dt_out * round(t_pilot / dt_out))
        if reference is None:
            if exact:
                sol = solve(system, x0, v0)

                def reference(t):
                    return sol.at(t)[0]
            else:
                ref_method = registry.method(registry.REFERENCE_ADAPTIVE, Options(1e-13, adaptive_atol(x0, v0, 1e-15),
                                                                                  progress=False))
                cache: dict = {}

                def reference(t):
                    key = (t.shape[0], float(t[-1]))
                    if key not in cache:
                        cache[key] = record(ref_method, system, x0, v0, Grid(float(t[1] - t[0]), t.shape[0] - 1)).x
                    return cache[key]
        laws = {}
        if adaptive:
            for m in registry.planned(Kind.ADAPTIVE):
                if (only is None or m.name in only) and m.refusal(system) is None:
                    laws[m] = calibrate_adaptive(m, system, x0, v0, t_pilot, dt_out, reference)
        planner = cls(float(t_end), float(dt_out), system.n, model, exact, tuple(steps_), responses, costs,
                      tuple(props), laws, modal_seconds)
        if not exact:
            planner = planner.calibrated(system, x0, v0, t_pilot, reference)
        return planner

    def calibrated(self, system: System, x0: np.ndarray, v0: np.ndarray, t_pilot: float,
                   reference: Callable) -> "Planner":
        """Scale each step method's (linearized) model by measured/predicted on one pilot run.

        The pilot step makes the linearized prediction about 1e-4 over ``t_pilot``; it is a
        multiple or a divisor of the output spacing, so the pilot's times lie on the reference grid
        (one reference run for all pilots).
        """
        pilot = Planner(t_pilot, self.dt_out, self.n, self.model, self.exact, self.step_methods, self.responses,
                        self.step_costs)
        grid = Grid.covering(t_pilot, self.dt_out)
        x_ref = reference(grid.t)
        spacing = grid.h
        factors = {}
        for m in self.step_methods:
            h_target = t_pilot / pilot.plan_step(m, 1e-4).steps
            if h_target >= spacing:
                h, stride = spacing * math.floor(h_target / spacing), 1
            else:
                stride = math.ceil(spacing / h_target)
                h = spacing / stride
            n = stride * math.floor(t_pilot / (h * stride) + 1e-9)
            tr = record(m, system, x0, v0, Grid(h, n, stride))
            idx = np.rint(tr.t / spacing).astype(int)
            measured = float(np.max(np.abs(tr.x - x_ref[idx])))
            predicted = pilot.model.envelope(self.responses[m], h, n)
            factors[m] = min(max(measured / max(predicted, 1e-300), 1.0 / 30.0), 30.0)
        return replace(self, calibration=factors)

    # -- predictions ---------------------------------------------------------------------------
    def predict_error(self, method: Method, steps: int, exact_budget: int = EXACT_BUDGET) -> tuple[float, str]:
        """Predicted error of ``steps`` steps of a step method over the horizon, and the model used."""
        resp = self.responses[method]
        h = self.t_end / steps
        m = self.model
        work = steps * max(m.omega.shape[0], 1) * self.n
        if work <= exact_budget:
            e, how = m.error(resp, h, steps), "closed-form numerical solution per mode"
        else:
            e, how = m.envelope(resp, h, steps), "per-mode envelope"
        if not self.exact:
            f = self.calibration.get(method)
            if f is not None:
                e *= f
                how += f" of the linearization x {f:.3g} (pilot-calibrated)"
            else:
                how += " (of the linearization: approximate)"
        return e + roundoff_floor(m.size, resp.stages, steps), how

    def min_steps(self, method: Method) -> int:
        """The fewest steps over the horizon inside the method's stability limit."""
        limit = method.traits.stability_limit
        w = self.model.omega_max
        if math.isinf(limit) and math.isfinite(method.traits.order):
            limit = math.pi  # unconditionally stable (Newmark, HHT): no accuracy beyond half a period per step
        if w == 0 or not math.isfinite(limit):
            return 1
        return max(1, math.floor(self.t_end * w / limit * (1 + 1e-12)) + 1)

    def plan_step(self, method: Method, tol: float) -> Candidate:
        """The fewest steps whose predicted error is at most ``SAFETY·tol``."""
        resp = self.responses[method]
        m = self.model
        cost = self.step_costs[method]
        target = SAFETY * tol
        n_lo = self.min_steps(method)

        scale = self.calibration.get(method, 1.0)

        def env(n):
            return scale * m.envelope(resp, self.t_end / n, n) + roundoff_floor(m.size, resp.stages, n)

        # exponential search on the envelope (monotone until the rounding floor takes over)
        n_hi, found = n_lo, False
        best_n, best_e = n_lo, env(n_lo)
        while n_hi <= MAX_STEPS:
            e = env(n_hi)
            if e < best_e:
                best_n, best_e = n_hi, e
            if e <= target:
                found = True
                break
            if n_hi > 64 * best_n:  # the floor is rising: no point refining further
                break
            n_hi *= 2
        if not found:
            h = self.t_end / best_n
            return Candidate(method, h, best_n, None, best_e, cost(best_n), False,
                             "rounding floor above the tolerance")
        lo = max(n_lo, n_hi // 2) if n_hi > n_lo else n_lo
        # refine on the envelope between lo (too few) and n_hi (enough)
        while lo < n_hi - 1 and env(lo) > target:
            mid = (lo + n_hi) // 2
            if env(mid) <= target:
                n_hi = mid
            else:
                lo = mid
        n = n_hi
        # with the exact closed form, walk down while it still meets the target
        if n * max(m.omega.shape[0], 1) * self.n <= EXACT_BUDGET:
            def exact(k):
                return self.predict_error(method, k)[0]
            lo = max(n_lo, n // 4)
            if exact(lo) <= target:
                n = lo
            else:
                while lo < n - 1:
                    mid = (lo + n) // 2
                    if exact(mid) <= target:
                        n = mid
                    else:
                        lo = mid
        e, how = self.predict_error(method, n)
        return Candidate(method, self.t_end / n, n, None, e, cost(n), e <= tol, how)

    def plan_adaptive(self, method: Method, tol: float) -> Candidate:
        law = self.adaptive[method]
        rtol = law.error.solve(SAFETY * tol, self.t_end)
        rtol = max(min(rtol, 1e-2), MIN_RTOL)
        # no integrator beats the rounding floor of the exact solution (a power law steeper than
        # rtol¹, as the high-order RKN pairs calibrate to, would otherwise promise 1e-17)
        floor = self.exact_error(self.output_grid.steps)
        error = max(law.error(rtol, self.t_end), floor)
        evals = law.evals(rtol, self.t_end)
        return Candidate(method, None, None, rtol, error, evals * law.seconds_per_eval,
                         error <= tol, "pilot-calibrated power law in rtol")

    def exact_error(self, steps: int) -> float:
        """Rounding-level error of the exact methods over ``steps`` output intervals."""
        m = self.model
        return EPS * m.size * (8.0 + m.omega_max * self.t_end + math.sqrt(steps))

    def propagator_error(self, steps: int) -> float:
        """Rounding-level error of an exact propagator (``expm``, ``chebyshev``) after ``steps`` steps."""
        return EPS * self.model.size * (8.0 + steps)

    def plan(self, tol: float) -> Plan:
        """Candidates for ``tol`` and the recommended (cheapest) one."""
        if not (math.isfinite(tol) and tol > 0):
            raise ValueError(f"tolerance must be finite and > 0, got {tol!r}")
        cands: list[Candidate] = []
        out = self.output_grid
        if self.exact:
            e = self.exact_error(out.steps)
            cands.append(Candidate(exact_method(), None, None, None, e, self.modal_seconds, e <= tol,
                                   "exact; error at the rounding level"))
        for m in self.step_methods:
            cands.append(self.plan_step(m, tol))
        for m in self.propagators:
            e = self.propagator_error(out.steps)
            cands.append(Candidate(m, out.h, out.steps, None, e, self.step_costs[m](out.steps), e <= tol,
                                   "exact propagator; rounding grows with the number of steps"))
        for m in self.adaptive:
            cands.append(self.plan_adaptive(m, tol))
        ok = tuple(c for c in cands if c.reachable)
        bad = tuple(c for c in cands if not c.reachable)
        if not ok:
            raise ValueError(f"no method reaches tol = {tol:g} over t = {self.t_end:g}: the rounding floors "
                             f"are above it (smallest predicted: {min(c.predicted_error for c in cands):.2g})")
        best = min(ok, key=lambda c: c.predicted_seconds)
        return Plan(tol, self.t_end, best, ok, bad)
