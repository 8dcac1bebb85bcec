"""Scaling to long chains: the exact solution's set-up against Verlet's per-step cost, N = 3 … 10⁶.

For each chain size N this measures, single-threaded and as the minimum of
repeats after a warm-up:

* exact-solution set-up: the dense route the ``modal`` method uses
  (:func:`numeric.modes.spectrum.spectrum`, an SVD, O(N³)), a dense symmetric
  eigen-solve (``scipy.linalg.eigh``, O(N³)), the tridiagonal solver with
  eigenvectors (``scipy.linalg.eigh_tridiagonal``, O(N²) memory) — these on
  an index-dependent ("random") chain, where nothing better exists — and the
  transform solution of a uniform chain (:mod:`numeric.exact.chain`,
  O(N log N) set-up and per output time, no matrix);
* the cost of one output time from stored eigenvectors (an N×N product);
* one velocity-Verlet step: the NumPy stencil path (the project's ``verlet``
  kernel on the generated module), the fused sweep (:mod:`numeric.compiled.fast`) and
  its multi-step half-step-velocity form;
* the memory floor: the time to move 32 bytes per mass (x and v read and
  written once), measured in the same run by a one-pass in-place update of
  two N-arrays (:func:`numeric.compiled.fast.stream_update`) and by a NumPy copy of
  2N doubles (16 bytes read + 16 written per mass); the floor is the faster.

The crossover answers "for this N, horizon T and tolerance, which is
cheaper?". Verlet's step comes from its error model: the phase error of the
fastest mode after time T is about ``ω_max³ h² T / 24`` (relative to the
amplitude), so ``h = √(24 tol / (ω_max³ T))``, capped at the stability edge
(``ω_max h < 2``, here 1.9), and ``steps = ⌈T/h⌉``. The exact method pays its
set-up and one evaluation at T. Equating the two gives the horizon T* beyond
which the exact solution is cheaper: ``T* = (c_exact / (c_step √(ω³/(24 tol))))^(2/3)``
while accuracy limits the step. Dense set-up costs beyond the largest measured
N are extrapolated (∝ N³, tridiagonal ∝ N²) and marked so.
"""

from __future__ import annotations

import math
import time
from dataclasses import InitVar, asdict, dataclass, field
from types import ModuleType
from typing import Callable

import numpy as np

from ...generated.contract import MAX_DENSE, End
from ..compiled import fast
from .timing import best_seconds, interleaved_samples, interleaved_seconds, single_threaded_blas
from ..exact.chain import ChainModal
from ..system import System

#: Default chain sizes of ``springchain scaling``.
DEFAULT_SIZES = (3, 10, 30, 100, 300, 1000, 2000, 4000, 10_000, 30_000, 100_000, 300_000, 1_000_000)
#: Bytes a Verlet step must move per mass at the least: x and v (8 bytes each) read and written.
FLOOR_BYTES_PER_MASS = 32
#: Largest ω_max·h used (stability edge 2).
STABLE_OMEGA_H = 1.9

#: Markdown columns (record field -> title): seconds per operation.
SECONDS_COLUMNS = {
    "n": "N",
    "setup_dense_svd": "dense SVD set-up (modal)",
    "setup_dense_eigh": "dense eigh set-up",
    "setup_tridiagonal": "eigh_tridiagonal set-up",
    "eval_dense": "eigenvectors: 1 output time",
    "setup_transform": "transform set-up (uniform)",
    "eval_transform": "transform: 1 output time",
    "step_numpy": "NumPy step",
    "step_fused": "fused step",
    "step_fused_advance": "fused multi-step, per step",
    "step_fused_sweep": "fused one-step sweeps, per step",
    "step_numpy_random": "NumPy step (random)",
    "step_fused_random": "fused step (random)",
}
#: Markdown columns: nanoseconds per mass and the crossover horizons (``ns:`` = seconds/N·1e9).
PER_MASS_COLUMNS = {
    "n": "N",
    "ns:step_numpy": "NumPy step ns/mass",
    "ns:step_fused": "fused step ns/mass",
    "ns:step_fused_advance": "fused multi-step ns/mass",
    "ns:step_fused_sweep": "one-step sweeps ns/mass",
    "ns:floor": "floor ns/mass (32 B)",
    "fused_over_floor": "multi-step / floor",
    "crossover_transform": "T* transform vs fused (uniform)",
    "crossover_dense": "T* best eigenvector route vs fused (random)",
    "cheaper_uniform": "cheaper at T (uniform)",
    "cheaper_random": "cheaper at T (random)",
}


@dataclass(frozen=True)
class ScalingConfig:
    """What :func:`run` measures.

    Attributes
    ----------
    sizes : tuple of int
        Chain sizes N.
    svd_max, dense_max, tridiagonal_max : int
        Largest N for the dense SVD route, ``scipy.linalg.eigh`` and
        ``eigh_tridiagonal`` with eigenvectors.
    t_end, tol : float
        Horizon and relative position tolerance of the crossover.
    budget : float
        Seconds of timed repeats per set-up measurement (at least one repeat).
    step_budget : float
        Seconds of interleaved rounds for the per-step costs and the floor at each N
        (four times as much at the largest N, the headline).
    memory_bytes : float
        Memory an eigenvector route may use: it needs about three N×N float64
        arrays (matrix, eigenvectors, workspace), so it is infeasible above
        ``N = √(memory_bytes / 24)`` (≈ 19 000 for 8 GiB), whatever its time.
    """

    sizes: tuple[int, ...] = DEFAULT_SIZES
    svd_max: int = 1000
    dense_max: int = 2000
    tridiagonal_max: int = 4000
    t_end: float = 1000.0
    tol: float = 1e-6
    budget: float = 0.25
    step_budget: float = 1.0
    memory_bytes: float = 8 * 2**30

    def __post_init__(self):
        if not self.sizes or min(self.sizes) < 3:
            raise ValueError(f"sizes must be chain sizes >= 3, got {self.sizes!r}")
        if not (self.t_end > 0 and 0 < self.tol < 1):
            raise ValueError(f"need t_end > 0 and 0 < tol < 1, got {self.t_end!r}, {self.tol!r}")


@dataclass(frozen=True)
class ScalingResult:
    """Records (one per N), the headline at the largest N, and the configuration."""

    config: ScalingConfig
    records: list[dict] = field(repr=False)
    headline: dict
    notes: tuple[str, ...] = ()

    def to_json(self) -> dict:
        return {"config": asdict(self.config), "records": self.records, "headline": self.headline,
                "notes": list(self.notes)}


# -- error model and crossover ---------------------------------------------------------------------
def verlet_step_for(t_end: float, tol: float, omega_max: float) -> float:
    """Verlet step meeting ``ω_max³ h² T / 24 <= tol`` (relative phase error), capped at ``1.9/ω_max``."""
    if omega_max <= 0:
        return t_end
    h = math.sqrt(24.0 * tol / (omega_max**3 * t_end))
    return min(h, STABLE_OMEGA_H / omega_max, t_end)


def verlet_steps(t_end: float, tol: float, omega_max: float) -> int:
    """``⌈T / h⌉`` for the step of :func:`verlet_step_for`."""
    return max(1, math.ceil(t_end / verlet_step_for(t_end, tol, omega_max) - 1e-9))


def crossover_time(c_exact: float, c_step: float, tol: float, omega_max: float) -> float:
    """The horizon T* at which Verlet's ``steps(T)·c_step`` equals the exact method's ``c_exact``.

    Beyond T* the exact solution is cheaper. Accuracy-limited steps give
    ``steps = T^(3/2) √(ω³/(24 tol))``; if the step that accuracy allows at T*
    is beyond the stability edge, ``steps = T ω / 1.9`` is used instead.
    """
    if omega_max <= 0 or c_step <= 0:
        return math.inf
    rate = math.sqrt(omega_max**3 / (24.0 * tol))
    t = (c_exact / (c_step * rate)) ** (2.0 / 3.0)
    if verlet_step_for(t, tol, omega_max) >= STABLE_OMEGA_H / omega_max:  # stability-limited there
        t = c_exact * STABLE_OMEGA_H / (c_step * omega_max)
    return t


# -- chains ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ChainCase:
    """A generated ``[chain]`` module at fixed parameters, evaluated at any N (built from the module,
    held as a :class:`System`)."""

    label: str
    module: InitVar[ModuleType]
    params: dict[str, float] = field(default_factory=dict)
    #: The module bound to ``params`` at its own N.
    base: System = field(init=False, repr=False)

    def __post_init__(self, module: ModuleType) -> None:
        object.__setattr__(self, "base", System.from_module(module, self.params))

    @property
    def values(self) -> dict[str, float]:
        """The parameter values (the module's defaults updated by ``params``)."""
        return dict(self.base.params)

    def system(self, n: int) -> System:
        """The chain at ``n`` masses."""
        return self.base.with_n(n)

    def arrays(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """masses (n,), spring_ends (S, 2), stiffness (S,)."""
        s = self.system(n)
        return s.masses, s.spring_ends, s.stiffness

    def initial(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """A smooth initial displacement (half sine) and zero velocity, shape (n, 1)."""
        i = np.arange(n, dtype=float)
        return (0.01 * np.sin(np.pi * (i + 1) / (n + 1)))[:, None], np.zeros((n, 1))


def _numpy_step(case: ChainCase, n: int, h: float) -> tuple[Callable, str]:
    """The project's ``verlet`` kernel on the generated stencil (or :mod:`numeric.compiled.fast`'s NumPy backend)."""
    system = case.system(n)
    acc = system.make_acceleration()
    try:
        from ..integrators.base import Problem
        from ..run import registry

        kernel = registry.implementation(registry.DEFAULT_STEP)().kernel(Problem(acc), h)
        return kernel, f"numeric.integrators {registry.DEFAULT_STEP} kernel"
    except Exception:  # the integrator package's API moved: time the same formula here
        fv = fast.FusedVerlet.from_system(system, h, fast.Backend.NUMPY)
        return fv.kernel(), "numeric.compiled.fast NumPy backend"


# -- measurements ---------------------------------------------------------------------------------------
def floor_calls(n: int) -> dict[str, tuple[Callable[[], object], int]]:
    """The two measurements of the 32-byte-per-mass floor, as calls for :func:`interleaved_seconds`.

    ``floor_stream``: the one-pass in-place update of two N-arrays
    (:func:`numeric.compiled.fast.stream_update`, numba; absent without it);
    ``floor_copy``: NumPy copying 2N doubles (16 bytes read and 16 written per mass).
    """
    x = np.random.default_rng(0).standard_normal(n)
    v = np.random.default_rng(1).standard_normal(n) * 1e-3
    src = np.random.default_rng(2).standard_normal(2 * n)
    dst = np.empty_like(src)
    calls = {"floor_copy": (lambda: np.copyto(dst, src), 1)}
    if fast.available():
        calls["floor_stream"] = (lambda: fast.stream_update(x, v), 1)
    return calls


def step_calls(case: ChainCase, n: int, prefix: str = "", advance_steps: int = 100) -> tuple[dict, str]:
    """Verlet-step calls (NumPy stencil path, fused step, fused multi-step) for :func:`interleaved_seconds`."""
    x0, v0 = case.initial(n)
    system = case.system(n)
    h = 0.5 * STABLE_OMEGA_H / fast.ChainCoefficients.from_system(system).omega_max_bound
    kernel, source = _numpy_step(case, n, h)
    a0 = system.make_acceleration()(x0)
    state = [x0.copy(), v0.copy(), a0.copy()]

    def numpy_step():
        state[0], state[1], state[2] = kernel(state[0], state[1], state[2], 0)

    calls = {prefix + "step_numpy": (numpy_step, 1)}
    if fast.available():
        fv = fast.FusedVerlet.from_system(system, h, fast.Backend.NUMBA)
        x, v, a = x0[:, 0].copy(), v0[:, 0].copy(), a0[:, 0].copy()
        calls[prefix + "step_fused"] = (lambda: fv.step(x, v, a, inplace=True), 1)
        if not prefix:
            calls["step_fused_advance"] = (lambda: fv.advance(x, v, a, advance_steps), advance_steps)
            calls["step_fused_sweep"] = (lambda: fv.advance(x, v, a, advance_steps, two_step_sweeps=False),
                                         advance_steps)
    return calls, source


def measure_step_costs(uniform: ChainCase, random: ChainCase, n: int, budget: float) -> dict:
    """Floor and per-step costs of both chains at size n, timed in turns (same conditions)."""
    calls = floor_calls(n)
    uni, source = step_calls(uniform, n)
    rnd, _ = step_calls(random, n, prefix="random:")
    calls.update(uni)
    calls.update(rnd)
    # each sample is several consecutive calls (≥ 20 ms), so the floor, like the multi-step sweep,
    # is measured on data that the previous pass left in cache, not after another call flushed it
    samples = interleaved_samples(calls, budget=budget, min_time=0.02)
    best = {name: float(min(v)) for name, v in samples.items()}
    out = {"numpy_source": source, "floor_stream": best.get("floor_stream"), "floor_copy": best["floor_copy"],
           "step_numpy": best["step_numpy"], "step_fused": best.get("step_fused"),
           "step_fused_advance": best.get("step_fused_advance"), "step_fused_sweep": best.get("step_fused_sweep"),
           "step_numpy_random": best["random:step_numpy"], "step_fused_random": best.get("random:step_fused")}
    out["floor"] = min(t for t in (out["floor_stream"], out["floor_copy"]) if t is not None)
    # paired ratios: each round's sweep over the same round's floor, median over rounds (robust to load
    # that changes between rounds, which the ratio of the two minima is not)
    floors = np.minimum(samples["floor_copy"], samples.get("floor_stream", samples["floor_copy"]))
    for key, name in (("fused_over_floor_paired", "step_fused_advance"),
                      ("fused_sweep_over_floor_paired", "step_fused_sweep"),
                      ("fused_step_over_floor_paired", "step_fused")):
        if name in samples:
            out[key] = float(np.median(np.asarray(samples[name]) / floors))
    return out


def measure_exact_uniform(case: ChainCase, n: int, budget: float) -> dict:
    """Transform solution: set-up (two forward transforms) and one output time."""
    x0, v0 = case.initial(n)
    x0, v0 = x0[:, 0], v0[:, 0]
    system = case.system(n)
    setup = best_seconds(lambda: ChainModal.from_system(system, x0, v0), budget=budget)
    sol = ChainModal.from_system(system, x0, v0)
    ev = best_seconds(lambda: sol.at(12.5), budget=budget)
    return {"setup_transform": setup, "eval_transform": ev, "basis": sol.basis.value}


def measure_exact_dense(case: ChainCase, n: int, config: ScalingConfig) -> dict:
    """Dense and tridiagonal set-ups (where N allows) and one output time from stored eigenvectors."""
    import scipy.linalg

    from ..modes.spectrum import spectrum

    system = case.system(n)
    m, ends, k = system.masses, system.spring_ends, system.stiffness
    out: dict = {"setup_dense_svd": None, "setup_dense_eigh": None, "setup_tridiagonal": None, "eval_dense": None}
    b = config.budget
    if n <= config.svd_max:
        out["setup_dense_svd"] = best_seconds(lambda: spectrum(m, ends, k), budget=b)
    if n <= config.dense_max:
        r = 1.0 / np.sqrt(m)
        K = system.stiffness_matrix() if n <= MAX_DENSE else None
        if K is not None:
            D = K * r[:, None] * r[None, :]
            out["setup_dense_eigh"] = best_seconds(lambda: scipy.linalg.eigh(D), budget=b)
    if n <= config.tridiagonal_max and system.ends[0] is not End.RING:
        diag, off = system.stiffness_bands()
        r = 1.0 / np.sqrt(m)
        d, e = diag * r * r, off * r[:-1] * r[1:]
        out["setup_tridiagonal"] = best_seconds(lambda: scipy.linalg.eigh_tridiagonal(d, e), budget=b)
    if n <= config.tridiagonal_max:
        E = np.random.default_rng(3).standard_normal((n, n))  # the product costs the same for any E
        q = np.random.default_rng(4).standard_normal(n)
        w = np.linspace(0.0, 2.0, n)
        out["eval_dense"] = best_seconds(lambda: E @ (q * np.cos(w * 12.5)), budget=b)
    return out


def _extrapolate(records: list[dict], key: str, n: int, power: float) -> float | None:
    """``t(N_max) (n/N_max)^power`` from the largest N where ``key`` was measured."""
    known = [(r["n"], r[key]) for r in records if r.get(key) is not None]
    if not known:
        return None
    n0, t0 = max(known)
    return t0 * (n / n0) ** power


def _crossovers(records: list[dict], config: ScalingConfig, omega_uniform: float, omega_random) -> list[str]:
    """Fill the cost model columns in place; returns notes on extrapolation."""
    notes = []
    for r in records:
        n = r["n"]
        steps = verlet_steps(config.t_end, config.tol, omega_uniform)
        r["verlet_steps"] = steps
        c_step = r.get("step_fused_advance") or r.get("step_fused") or r["step_numpy"]
        r["cost_verlet"] = steps * c_step
        if r.get("setup_transform") is not None:
            c_exact = r["setup_transform"] + r["eval_transform"]
            r["cost_exact_transform"] = c_exact
            r["crossover_transform"] = crossover_time(c_exact, c_step, config.tol, omega_uniform)
            r["cheaper_uniform"] = "exact (transform)" if c_exact < r["cost_verlet"] else "verlet (fused)"
        # random chain: the best dense route, measured or extrapolated
        w = omega_random[n]
        c_step_r = r.get("step_fused_random") or r["step_numpy_random"]
        ev = r.get("eval_dense") if r.get("eval_dense") is not None else _extrapolate(records, "eval_dense", n, 2.0)
        options = {}
        extrapolated = set()
        for key, power in (("setup_dense_eigh", 3.0), ("setup_tridiagonal", 2.0), ("setup_dense_svd", 3.0)):
            t = r.get(key)
            if t is None:
                t = _extrapolate(records, key, n, power)
                extrapolated.add(key)
            if t is not None:
                options[key] = t + (ev or 0.0)
        steps_r = verlet_steps(config.t_end, config.tol, w)
        r["cost_verlet_random"] = steps_r * c_step_r
        feasible = 24.0 * n * n <= config.memory_bytes
        r["dense_feasible"] = feasible
        if options and feasible:
            best = min(options, key=options.get)
            r["cost_exact_dense"] = options[best]
            r["exact_dense_route"] = best.replace("setup_", "")
            r["exact_dense_extrapolated"] = best in extrapolated
            r["crossover_dense"] = crossover_time(options[best], c_step_r, config.tol, w)
            r["cheaper_random"] = ("exact (" + r["exact_dense_route"] + ")"
                                   if options[best] < r["cost_verlet_random"] else "verlet (fused)")
        elif options:
            r["crossover_dense"] = math.inf
            r["cheaper_random"] = f"verlet (N×N eigenvectors need {24.0 * n * n / 2**30:.0f} GiB)"
    if any(r.get("exact_dense_extrapolated") for r in records):
        notes.append("dense set-up costs beyond the largest measured N are extrapolated (eigh, SVD ∝ N³; "
                     "eigh_tridiagonal ∝ N²; one eigenvector evaluation ∝ N²)")
    return notes


def run(uniform: ChainCase, random: ChainCase, config: ScalingConfig = ScalingConfig(),
        progress: Callable[[str], None] | None = None) -> ScalingResult:
    """Measure every quantity for every N (single-threaded BLAS) and build the crossover table.

    Parameters
    ----------
    uniform : ChainCase
        A uniform ``[chain]`` module (transform solution, uniform fused kernel).
    random : ChainCase
        An index-dependent ``[chain]`` module (dense routes, index-dependent fused kernel).
    progress : callable, optional
        Called with one line of text per stage.
    """
    say = progress or (lambda line: None)
    records: list[dict] = []
    omega_random: dict[int, float] = {}
    omega_uniform = fast.ChainCoefficients.from_system(uniform.system(3)).omega_max_bound
    with single_threaded_blas():
        if fast.available():
            say("compiling the fused kernels (numba; cached after the first run)")
            for case in (uniform, random):
                for fn, _ in step_calls(case, 16, advance_steps=2)[0].values():
                    fn()
        sizes = sorted(set(config.sizes))
        for j, n in enumerate(sizes):
            t0 = time.perf_counter()
            rec: dict = {"n": n}
            budget = config.step_budget * (4.0 if n == sizes[-1] else 1.0)  # the headline gets more rounds
            rec.update(measure_step_costs(uniform, random, n, budget))
            rec.update(measure_exact_uniform(uniform, n, config.budget))
            rec.update(measure_exact_dense(random, n, config))
            if rec.get("step_fused_advance"):
                rec["fused_over_floor"] = rec["step_fused_advance"] / rec["floor"]
                rec["fused_sweep_over_floor"] = rec["step_fused_sweep"] / rec["floor"]
                rec["fused_step_over_floor"] = rec["step_fused"] / rec["floor"]
            omega_random[n] = fast.ChainCoefficients.from_system(random.system(n)).omega_max_bound
            records.append(rec)
            say(f"N = {n:>8d}  ({j + 1}/{len(sizes)}, {time.perf_counter() - t0:.1f} s): "
                f"numpy step {_ns(rec['step_numpy'], n)}, fused {_ns(rec.get('step_fused'), n)}, "
                f"multi-step {_ns(rec.get('step_fused_advance'), n)}, floor {_ns(rec['floor'], n)} per mass")
    notes = _crossovers(records, config, omega_uniform, omega_random)
    notes.append("below about 10⁴ masses the per-step and floor times are dominated by per-call overhead "
                 "(Python and kernel dispatch, ~0.2–5 µs), so per-mass figures there do not measure memory")
    if not all(r.get("dense_feasible", True) for r in records):
        notes.append(f"eigenvector routes are infeasible where three N×N float64 arrays exceed "
                     f"{config.memory_bytes / 2**30:g} GiB (N > {math.isqrt(int(config.memory_bytes / 24)):,})")
    if not fast.available():
        notes.append("numba is not installed: no fused kernel (install the `fast` extra)")
    big = records[-1]
    n = big["n"]
    head = {"n": n,
            "ns_per_mass": {key: (None if big.get(key) is None else 1e9 * big[key] / n)
                            for key in ("step_numpy", "step_fused", "step_fused_advance", "step_fused_sweep",
                                        "floor_stream", "floor_copy", "floor", "step_numpy_random",
                                        "step_fused_random")},
            "fused_over_floor": big.get("fused_over_floor"),
            "fused_sweep_over_floor": big.get("fused_sweep_over_floor"),
            "fused_step_over_floor": big.get("fused_step_over_floor"),
            "fused_over_floor_paired": big.get("fused_over_floor_paired"),
            "fused_sweep_over_floor_paired": big.get("fused_sweep_over_floor_paired"),
            "fused_step_over_floor_paired": big.get("fused_step_over_floor_paired"),
            "target_ratio": 1.5,
            "numpy_source": big.get("numpy_source")}
    # the verdict uses the median of per-round ratios (sweep and floor timed back to back): under a
    # changing load the two minima may come from different moments
    verdict = head["fused_over_floor_paired"] or head["fused_over_floor"]
    head["target_met"] = None if verdict is None else bool(verdict <= head["target_ratio"])
    return ScalingResult(config, records, head, tuple(notes))


def _ns(seconds, n) -> str:
    return "   -   " if seconds is None else f"{1e9 * seconds / n:7.3f} ns"


def print_progress(line: str) -> None:
    """One progress line on stderr, ``scaling: ...`` (:meth:`numeric.progress.Reporter.say`)."""
    from ..progress import Reporter

    Reporter("scaling", prefix="scaling").say(line)


__all__ = ["ScalingConfig", "ScalingResult", "ChainCase", "run", "best_seconds",
           "verlet_step_for", "verlet_steps", "crossover_time", "interleaved_seconds", "DEFAULT_SIZES",
           "FLOOR_BYTES_PER_MASS"]
