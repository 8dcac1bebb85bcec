"""The benchmark's data: one record per run, the sweep configuration, the result, and the targets
evaluated on the records (see :mod:`springchain.numeric.bench.workprecision` for what is measured)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..io.array_record import array_record
from ..run import registry
from ..run.protocol import Kind

#: Accuracies at which the targets are evaluated.
LINEAR_TARGET_ACCURACIES = tuple(10.0 ** -k for k in range(3, 13))
NONLINEAR_TARGET_ACCURACIES = tuple(10.0 ** -k for k in range(3, 10))
#: Required speed-ups: fastest method vs DOP853 (exact scenes); best integrator vs DOP853 (others).
LINEAR_TARGET_RATIO = 100.0
NONLINEAR_TARGET_RATIO = 3.0


# -- records ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BenchRecord:
    """One run of the benchmark (see the module docstring for the meaning of each field)."""

    method: str
    setting: str
    dt: float | None
    rtol: float | None
    steps: int | None
    error: float
    energy_error: float
    final_energy_norm_error: float
    seconds: float
    force_evals: int
    predicted_error: float | None
    repeats: int = 1

    def as_json(self) -> dict:
        def num(v):
            return None if v is None else float(v)

        return {"method": self.method, "setting": self.setting, "error": num(self.error),
                "energy_error": num(self.energy_error), "seconds": num(self.seconds),
                "force_evals": int(self.force_evals), "predicted_error": num(self.predicted_error),
                "final_energy_norm_error": num(self.final_energy_norm_error), "dt": num(self.dt),
                "rtol": num(self.rtol), "steps": self.steps, "repeats": self.repeats}


@dataclass(frozen=True)
class BenchConfig:
    """Sweep sizes. ``quick`` is the bounded version used by the tests.

    Attributes
    ----------
    eval_cap : int
        Largest force evaluations of one fixed-step run in the sweep, per 100 time units of horizon.
    adaptive_cap : int
        An adaptive method's sweep stops after a run with more evaluations (per 100 time units).
    adaptive_seconds_cap : float
        ... or after a run longer than this many seconds (its tighter tolerances only cost more;
        keeps a long horizon on a nonlinear scene within minutes).
    target_errors : tuple of float
        Errors the fixed-step sweep aims at (through the planner's model; linear scenes).
    rtols : tuple of float
    timing_budget : float
        Seconds of timed repeats per run.
    horizons_measured, horizons_model : tuple of float
        Error-vs-horizon study: horizons run, and horizons predicted by the model.
    horizon_eval_cap : int
        Force evaluations per method in the horizon study (longer horizons are modelled).
    """

    quick: bool = False
    eval_cap: int = 200_000
    adaptive_cap: int = 200_000
    adaptive_seconds_cap: float = 4.0
    target_errors: tuple = tuple(10.0 ** -k for k in range(1, 14))
    rtols: tuple = tuple(10.0 ** -k for k in range(3, 14))
    dop853_rtols: tuple = tuple(10.0 ** (-k / 2) for k in range(6, 28))
    timing_budget: float = 0.3
    horizons_measured: tuple = (1e2, 1e3, 1e4)
    horizons_model: tuple = (1e2, 1e3, 1e4, 1e5, 1e6)
    horizon_eval_cap: int = 320_000
    horizon_work: float = 32.0
    horizon_dop853_rtol: float = 1e-9
    horizon_dop853_cap: float = 1e3

    @classmethod
    def quick_config(cls) -> "BenchConfig":
        return cls(True, eval_cap=6_000, adaptive_cap=8_000, target_errors=(1e-2, 1e-5, 1e-8),
                   rtols=(1e-4, 1e-7), dop853_rtols=(1e-4, 1e-7), timing_budget=0.02, horizons_measured=(1e2,),
                   horizons_model=(1e2, 1e4, 1e6), horizon_eval_cap=5_000, horizon_dop853_cap=1e2)


@array_record
class HorizonCurve:
    """Error against horizon for one method at one setting.

    measured_t, measured_error, measured_energy : ndarray — horizons actually run;
    model_t, model_error : ndarray — the model's prediction (empty if none);
    model_label : str.
    """

    method: str
    setting: str
    measured_t: np.ndarray
    measured_error: np.ndarray
    measured_energy: np.ndarray
    model_t: np.ndarray
    model_error: np.ndarray
    model_label: str = ""


@dataclass(frozen=True)
class BenchResult:
    scene: str
    t_end: float
    exact: bool
    reference: str
    records: tuple[BenchRecord, ...]
    horizons: tuple[HorizonCurve, ...] = ()
    notes: tuple[str, ...] = ()
    derive_seconds: float | None = None

    def targets(self) -> dict:
        """The issue's targets evaluated on these records (see :func:`targets`)."""
        return targets(self.records, self.exact)

    def as_json(self) -> dict:
        return {"scene": self.scene, "t_end": self.t_end, "reference": self.reference,
                "derive_seconds": self.derive_seconds, "notes": list(self.notes),
                "records": [r.as_json() for r in self.records], "targets": self.targets()}


# -- targets -------------------------------------------------------------------------------------------
def _cheapest(records, accuracy: float, key: str, pick: Callable[[BenchRecord], bool]):
    ok = [r for r in records if pick(r) and r.error <= accuracy]
    return min(ok, key=lambda r: getattr(r, key)) if ok else None


def _compiled_peer(records, acc: float, best) -> dict:
    """The fastest ``dop853-compiled`` run reaching ``acc`` and ``best``'s speed-up over it (None without it)."""
    peer = _cheapest(records, acc, "seconds", lambda r: r.method == registry.COMPILED_PEER)
    return {"dop853_compiled_seconds": peer and peer.seconds,
            "compiled_ratio": peer.seconds / best.seconds if peer and best else None}


def targets(records: tuple[BenchRecord, ...], exact: bool) -> dict:
    """The issue's targets from the records.

    Exact scenes: for each accuracy 1e-3 … 1e-12 the fastest run reaching it
    against the fastest DOP853 run reaching it (needs ≥ 100×). Other scenes:
    for 1e-3 … 1e-9 the best fixed-step integrator against DOP853, in force
    evaluations and in seconds (needs ≥ 3× in both).
    """
    rows = []
    fixed = set(registry.names(Kind.STEP))
    reference = registry.REFERENCE_ADAPTIVE
    if exact:
        for acc in LINEAR_TARGET_ACCURACIES:
            best = _cheapest(records, acc, "seconds", lambda r: True)
            dop = _cheapest(records, acc, "seconds", lambda r: r.method == reference)
            ratio = dop.seconds / best.seconds if best and dop else None
            rows.append({"accuracy": acc, "fastest": best and best.method, "fastest_setting": best and best.setting,
                         "fastest_seconds": best and best.seconds, "dop853_setting": dop and dop.setting,
                         "dop853_seconds": dop and dop.seconds, "speedup": ratio, **_compiled_peer(records, acc, best),
                         "met": bool(ratio is not None and ratio >= LINEAR_TARGET_RATIO)})
        return {"kind": "fastest vs dop853 (seconds)", "required": LINEAR_TARGET_RATIO, "rows": rows}
    for acc in NONLINEAR_TARGET_ACCURACIES:
        dop_e = _cheapest(records, acc, "force_evals", lambda r: r.method == reference)
        dop_s = _cheapest(records, acc, "seconds", lambda r: r.method == reference)
        best_e = _cheapest(records, acc, "force_evals", lambda r: r.method in fixed)
        best_s = _cheapest(records, acc, "seconds", lambda r: r.method in fixed)
        re_ = dop_e.force_evals / best_e.force_evals if dop_e and best_e else None
        rs = dop_s.seconds / best_s.seconds if dop_s and best_s else None
        rows.append({"accuracy": acc, "best_evals": best_e and f"{best_e.method} {best_e.setting}",
                     "best_force_evals": best_e and best_e.force_evals,
                     "dop853_force_evals": dop_e and dop_e.force_evals, "evals_ratio": re_,
                     "best_seconds_run": best_s and f"{best_s.method} {best_s.setting}",
                     "best_seconds": best_s and best_s.seconds, "dop853_seconds": dop_s and dop_s.seconds,
                     "seconds_ratio": rs, **_compiled_peer(records, acc, best_s),
                     "met": bool(re_ is not None and rs is not None and re_ >= NONLINEAR_TARGET_RATIO
                                 and rs >= NONLINEAR_TARGET_RATIO)})
    return {"kind": "best fixed-step integrator vs dop853 (force evaluations and seconds)",
            "required": NONLINEAR_TARGET_RATIO, "rows": rows}
