"""Work–precision on the Duffing chain over a long horizon: every nonlinear-capable method against DOP853.

Run ``python benchmarks/duffing.py [--t-end 1000] [--frames 10] [--json]``. In one
process, with BLAS pinned to one thread, it integrates the bundled ``duffing`` scene (three
masses, cubic springs) from its initial state over ``[0, T]`` with

* SciPy's DOP853 and the embedded Runge–Kutta–Nyström pairs ``dprkn6``, ``dprkn8``,
  ``dprkn12``, each over a sweep of tolerances ``rtol = 10^(−k/2)`` (``atol`` as in
  ``springchain bench``), stopping once the error is below 1e-11, no longer improves, or a run costs more than
  ``EVAL_CAP`` evaluations;
* the best fixed-step method of the symplectic family, ``blanes-moan6``, over a sweep of steps.

*error* is the largest absolute position error over ``frames + 1`` equally spaced times
(``t = 0, T/frames, …, T``; by default every 100 time units, the final state included — the
error of every method grows with t, so the last frames decide), against a reference from Kahan–Li 8
at a small step whose own error is estimated from a second run at twice the step (and
cross-checked against DOP853 at its tightest tolerance). The RKN pairs step exactly onto
these times (no interpolation: each frame costs on average half a step, about 1.5 % of the
evaluations at 10 frames, 13 % at 100); DOP853 uses its dense output. The sweeps run
interleaved (at each sweep index every method once) so that changes of machine load hit all
methods alike; *seconds* is the minimum of at least two timed repeats of the whole run; *evals* counts force evaluations.

For each accuracy 1e-3 … 1e-10 the cost of each method to reach it is read off its sweep by
log–log interpolation between the two runs that bracket it on the sweep's Pareto front (runs
beaten by a cheaper-or-equal run are dropped), and divided into DOP853's. The
target (issue 13): the best method ≥ 3× DOP853 in force evaluations and in seconds at every
accuracy.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np
import importlib.util
from pathlib import Path

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

ACCURACIES = tuple(10.0 ** -k for k in range(3, 11))
TARGET = 3.0
ADAPTIVE_METHODS = ("dprkn6", "dprkn8", "dprkn12")
STEP_METHODS = ("blanes-moan6",)
#: A method's sweep stops after a run with more force evaluations than this.
EVAL_CAP = 400_000


def _setup(t_end: float, frames: int):
    from springchain import _api
    from springchain._modules import system_of
    from springchain.numeric.run.grid import Grid

    scene = _api.load("duffing")
    system, _ = system_of(scene)
    return system, np.asarray(scene.x0, float), np.asarray(scene.v0, float), Grid(t_end / frames, frames)


def reference(system, x0, v0, t_end: float, frames: int, h: float, progress=print):
    """Kahan–Li 8 at step ``h`` (and ``2h`` for its error estimate) on the frames; also its difference
    from DOP853 at rtol 1e-13."""
    from springchain.numeric.bench.reference import GridReference

    spacing = t_end / frames
    m_fine = max(2, int(math.ceil(spacing / h)))
    m_fine += m_fine % 2
    ref = GridReference.kahan_li(system, x0, v0, t_end, spacing, m_fine, m_fine // 2, progress)
    return ref


def _envelope(runs: list[dict], key: str) -> list[tuple[float, float]]:
    """The Pareto front (cost, error), sorted by cost: runs beaten by a cheaper-or-equal run are dropped."""
    out: list[tuple[float, float]] = []
    for cost, err in sorted((r[key], r["error"]) for r in runs):
        if not out or err < out[-1][1]:
            out.append((cost, err))
    return out


def cost_at(runs: list[dict], accuracy: float, key: str) -> float | None:
    """Interpolated cost (``key``: ``evals`` or ``seconds``) to reach ``accuracy``; None if no run reaches it."""
    env = _envelope(runs, key)
    for i, (cost, err) in enumerate(env):
        if err <= accuracy:
            if i == 0:
                return cost
            c0, e0 = env[i - 1]
            f = (math.log(accuracy) - math.log(e0)) / (math.log(err) - math.log(e0))
            return math.exp(math.log(c0) + f * (math.log(cost) - math.log(c0)))
    return None


def ratio_table(runs: dict[str, list[dict]]) -> list[dict]:
    """Per accuracy: DOP853's cost and each method's ratio (DOP853 / method) in evals and seconds."""
    rows = []
    for acc in ACCURACIES:
        dop_e, dop_s = cost_at(runs["dop853"], acc, "evals"), cost_at(runs["dop853"], acc, "seconds")
        row = {"accuracy": acc, "dop853_evals": dop_e, "dop853_seconds": dop_s, "methods": {}}
        for name, rs in runs.items():
            if name == "dop853":
                continue
            e, s = cost_at(rs, acc, "evals"), cost_at(rs, acc, "seconds")
            row["methods"][name] = {"evals": e, "seconds": s,
                                    "evals_ratio": dop_e / e if e and dop_e else None,
                                    "seconds_ratio": dop_s / s if s and dop_s else None}
        both = {n: min(m["evals_ratio"] or 0.0, m["seconds_ratio"] or 0.0) for n, m in row["methods"].items()}
        best = max(both, key=both.get) if both else None
        row["best"] = best
        row["met"] = bool(best and both[best] >= TARGET)
        rows.append(row)
    return rows


def _settings(name: str, frames):
    """The sweep of one method: ``(label, method, grid)`` per index k = 0, 1, … (tightening)."""
    from springchain.numeric.plan.planner import with_tolerance
    from springchain.numeric.run import registry
    from springchain.numeric.run.grid import Grid
    from springchain.numeric.run.protocol import Kind, Options

    method = registry.method(name, Options(progress=False))
    if method.kind is Kind.ADAPTIVE:
        for k in range(6, 31):
            rtol = 10.0 ** (-k / 2)
            if name == registry.REFERENCE_ADAPTIVE and rtol < 2.3e-14:  # SciPy's floor (it would raise rtol)
                return
            yield f"rtol={rtol:.2g}", (lambda x0, v0, rtol=rtol: with_tolerance(method, x0, v0, rtol)), frames
        return
    spacing = frames.h
    for k in range(0, 40):
        m = int(math.ceil(spacing / (2.0 * 2.0 ** (-k / 2))))  # h ≈ 2·2^(−k/2), a whole number per frame
        yield f"h={spacing / m:.4g}", (lambda x0, v0: method), Grid(spacing / m, frames.steps * m, m)


def run(t_end: float = 1000.0, frames: int = 10, budget: float = 0.5, ref_h: float = 0.025,
        progress=print) -> dict:
    """The sweeps, interleaved: at each sweep index every still-running method runs once (so a
    change in machine load between runs hits all methods alike)."""
    from springchain.numeric.run.protocol import record
    from springchain.numeric.bench.timing import measure, single_threaded_blas

    names = ("dop853", *ADAPTIVE_METHODS, *STEP_METHODS)
    with single_threaded_blas():
        system, x0, v0, out = _setup(t_end, frames)
        ref = reference(system, x0, v0, t_end, frames, ref_h, progress)
        xr = ref.x
        runs: dict[str, list[dict]] = {n: [] for n in names}
        sweeps = {n: _settings(n, out) for n in names}
        best = {n: math.inf for n in names}
        while sweeps:
            for name in list(sweeps):
                item = next(sweeps[name], None)
                if item is None:
                    del sweeps[name]
                    continue
                label, make, grid = item
                method = make(x0, v0)
                with np.errstate(all="ignore"):  # a fixed step beyond the stability limit overflows
                    timing = measure(lambda: record(method, system, x0, v0, grid), budget=budget, min_repeats=2,
                                     max_repeats=3)
                x, evals = timing.result.x, timing.result.force_evals
                err = float(np.max(np.abs(x - xr)))
                err = err if math.isfinite(err) else math.inf
                runs[name].append({"setting": label, "error": err, "evals": int(evals), "seconds": timing.seconds})
                progress(f"{name:>12} {label:>14}: error {err:9.2e}  {evals:8d} evals {timing.seconds:8.3f} s")
                if err < 1e-11 or (err > 0.5 * best[name] and err < 1e-9) or evals > EVAL_CAP:
                    del sweeps[name]
                best[name] = min(best[name], err)
    dop_tight = min(runs["dop853"], key=lambda r: r["error"])
    return {"scene": "duffing", "t_end": t_end, "frames": frames + 1,
            "reference": ref.description, "reference_error": ref.accuracy,
            "dop853_tightest_error": dop_tight["error"],
            "runs": runs, "rows": ratio_table(runs), "target": TARGET}


def _fmt(v, spec):
    return "–" if v is None else format(v, spec)


def markdown(result: dict) -> str:
    """The ratio table: per accuracy, DOP853's cost and each method's speed-up in evals / seconds."""
    names = list(result["rows"][0]["methods"])
    head = ("| accuracy | DOP853 evals | DOP853 s | " + " | ".join(f"{n} evals× / s×" for n in names)
            + " | best | ≥ 3× both |")
    lines = [head, "|" + "---|" * (5 + len(names))]
    for row in result["rows"]:
        cells = [f"{row['accuracy']:.0e}", _fmt(row["dop853_evals"], ".0f"), _fmt(row["dop853_seconds"], ".3f")]
        for n in names:
            m = row["methods"][n]
            cells.append(f"{_fmt(m['evals_ratio'], '.2f')} / {_fmt(m['seconds_ratio'], '.2f')}")
        cells += [row["best"] or "–", "met" if row["met"] else "missed"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python benchmarks/duffing.py", description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=1000.0, help="horizon T (default 1000)")
    ap.add_argument("--frames", type=int, default=10, help="error measured at frames+1 equally spaced times")
    ap.add_argument("--budget", type=float, default=0.5, help="seconds of timed repeats per run")
    ap.add_argument("--json", action="store_true", help="print the result as JSON instead of the table")
    _report.add_option(ap)
    args = ap.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        if not (args.t_end > 0 and args.frames >= 1):
            ap.error("--t-end must be > 0 and --frames >= 1")
        result = run(args.t_end, args.frames, args.budget, progress=lambda s: print(s, file=sys.stderr, flush=True))
        if args.json:
            print(json.dumps(result, indent=1))
            return 0
        print(f"duffing, T = {result['t_end']:g}, error = max position error over {result['frames']} frames")
        print(f"reference: {result['reference']}; DOP853's tightest run differs by {result['dop853_tightest_error']:.1e}")
        print("ratios = DOP853 cost / method cost at equal accuracy (log-log interpolated on each sweep)")
        print(markdown(result))
        return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
