"""Small scenes at compiled speed: what a step, an accuracy and the exact solution cost.

Run ``python benchmarks/bench_small.py [--steps 1000000] [--t-end 1000] [--json]``. In one process,
with BLAS pinned to one thread, side by side:

1. **Verlet on the seed** (3 masses, dt = 0.1) for ``--steps`` steps through the method protocol
   (``registry.method("verlet")``, the compiled loop, every 1000th frame recorded) against a
   hand-written numba Verlet loop on the same system (its acceleration typed in by hand from the
   scene: m, 3m, m and two springs k; recording the same frames), timed in turns, in ns per step;
   the recorded frames are compared.
2. **Duffing over T = 1000** (three masses, cubic springs; error = max |x − x_ref| at t = T, the
   reference Kahan–Li 8 compiled at h = 1/400, checked against the compiled DOP853 at rtol 1e-13):
   the fixed-step methods (compiled) over a sweep of steps and the RKN pairs ``dprkn8``, ``dprkn12``
   (compiled) over tolerances; SciPy's ``solve_ivp(method="DOP853")``
   the way a user calls it (a NumPy right-hand side on (N,) arrays, the generated ``acceleration``);
   and the compiled DOP853 (:func:`springchain.numeric.compiled.run.dop853`: SciPy's tableau and
   step control in numba), each over ``rtol = 10^(−k/2)``, ``atol = rtol/1000``. For each accuracy
   1e-3 … 1e-10 the seconds to reach it are read off each sweep's Pareto front by log–log
   interpolation; the best springchain method is compared with both DOP853s.
3. **The seed's exact solution** (``modal``, the accurate SVD spectrum, S = 1001 output times)
   against the sin/cos floor (``np.cos``/``np.sin`` of the N·S phases), timed in turns: the
   evaluation (modes computed), with the spectrum's set-up (a fresh system), and the API call
   ``springchain.simulate`` (see :func:`exact_vs_floor`).

Compile time (or loading from the disk cache) is reported once, separately, and is in no timing.
Timings are the minimum of repeats (:func:`springchain.numeric.bench.timing.measure`).
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np
import importlib.util
import sys
from pathlib import Path

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

ACCURACIES = tuple(10.0 ** -k for k in range(3, 11))
STEP_METHODS = ("verlet", "yoshida4", "blanes-moan4", "blanes-moan6", "kahan-li8")
RKN_METHODS = ("dprkn8", "dprkn12")


def _system(name):
    from springchain import _api
    from springchain._modules import system_of

    scene = _api.load(name)
    system, _ = system_of(scene)
    return system, np.asarray(scene.x0, float), np.asarray(scene.v0, float)


def _timed(run, budget=0.5):
    from springchain.numeric.bench.timing import measure

    t = measure(run, budget=budget, min_repeats=1)
    return t.seconds, t.result


# -- 1. Verlet per step ----------------------------------------------------------------------------
def _hand_verlet():
    import numba

    @numba.njit(cache=True)
    def loop(x, v, h, steps, k, m, rec, xs, vs):
        """The seed typed in by hand (m, 3m, m; two springs k), accelerations kept in registers; records
        the same frames as springchain's loop (step indices ``rec``) into ``xs``, ``vs``."""
        a0 = -k * (x[0] - x[1]) / m
        a1 = (k * (x[0] - x[1]) - k * (x[1] - x[2])) / (3 * m)
        a2 = k * (x[1] - x[2]) / m
        for r in range(3):
            xs[0, r] = x[r]
            vs[0, r] = v[r]
        j = 1
        for i in range(steps):
            x[0] += h * v[0] + 0.5 * h * h * a0
            x[1] += h * v[1] + 0.5 * h * h * a1
            x[2] += h * v[2] + 0.5 * h * h * a2
            b0 = -k * (x[0] - x[1]) / m
            b1 = (k * (x[0] - x[1]) - k * (x[1] - x[2])) / (3 * m)
            b2 = k * (x[1] - x[2]) / m
            v[0] += 0.5 * h * (a0 + b0)
            v[1] += 0.5 * h * (a1 + b1)
            v[2] += 0.5 * h * (a2 + b2)
            a0, a1, a2 = b0, b1, b2
            if j < rec.shape[0] and rec[j] == i + 1:
                for r in range(3):
                    xs[j, r] = x[r]
                    vs[j, r] = v[r]
                j += 1
        return x, v

    return loop


def verlet_per_step(steps: int, budget: float = 4.0) -> dict:
    """springchain's Verlet (the method protocol into a memory recorder, the compiled loop) and the hand
    loop, both recording every 1000th step, timed in turns (:func:`~numeric.bench.timing.interleaved_seconds`)."""
    from springchain.numeric.run import registry
    from springchain.numeric.run.grid import Grid
    from springchain.numeric.run.protocol import Options, record
    from springchain.numeric.bench.timing import interleaved_seconds

    system, x0, v0 = _system("seed")
    h = 0.1
    method = registry.method("verlet", Options(progress=False))
    grid = Grid(h, steps, 1000)
    record(method, system, x0, v0, Grid(h, 10, 1))  # compile/load once, outside the timing
    hand = _hand_verlet()
    rec = np.arange(0, steps + 1, 1000)
    xs, vs = np.empty((rec.shape[0], 3)), np.empty((rec.shape[0], 3))
    secs = interleaved_seconds({"ours": (lambda: record(method, system, x0, v0, grid), steps),
                                "hand": (lambda: hand(x0.copy(), v0.copy(), h, steps, 1.0, 1.0, rec, xs, vs), steps)},
                               budget=budget, min_rounds=5)
    run = record(method, system, x0, v0, grid)
    hand(x0.copy(), v0.copy(), h, steps, 1.0, 1.0, rec, xs, vs)
    diff = float(np.max(np.abs(run.x - xs)))
    return {"steps": steps, "record_every": 1000, "springchain_ns": 1e9 * secs["ours"],
            "hand_numba_ns": 1e9 * secs["hand"], "ratio": secs["ours"] / secs["hand"],
            "final_state_difference": diff, "largest_position": float(np.max(np.abs(xs)))}


# -- 2. Duffing work-precision ---------------------------------------------------------------------
def _envelope(runs):
    out = []
    for cost, err in sorted((r["seconds"], r["error"]) for r in runs):
        if not out or err < out[-1][1]:
            out.append((cost, err))
    return out


def cost_at(runs, accuracy):
    """Seconds to reach ``accuracy`` (log–log interpolation on the Pareto front), or None."""
    env = _envelope(runs)
    for i, (cost, err) in enumerate(env):
        if err <= accuracy:
            if i == 0:
                return cost
            c0, e0 = env[i - 1]
            f = (math.log(accuracy) - math.log(e0)) / (math.log(err) - math.log(e0))
            return math.exp(math.log(c0) + f * (math.log(cost) - math.log(c0)))
    return None


def duffing(t_end: float, say=print) -> dict:
    from scipy.integrate import solve_ivp

    from springchain.numeric.compiled.run import dop853
    from springchain.numeric.run import registry
    from springchain.numeric.run.grid import Grid
    from springchain.numeric.run.protocol import Options, record

    system, x0, v0 = _system("duffing")
    n = system.n
    params = dict(system.params)
    acc = system.module.acceleration

    def final(name, steps):
        m = registry.method(name, Options(progress=False))
        return record(m, system, x0, v0, Grid(t_end / steps, steps, steps)).x[-1]

    for name in STEP_METHODS:  # compile/load every loop once, outside the timings
        final(name, 10)
    dop853(system, x0, v0, 1.0, 1e-6, 1e-9)
    x_ref = final("kahan-li8", int(400 * t_end))
    x_ref2 = final("kahan-li8", int(200 * t_end))
    x_dop = dop853(system, x0, v0, t_end, 1e-13, 1e-16)[0]
    ref_err = float(np.max(np.abs(x_ref2 - x_ref))) / 255.0  # order 8: the error at h/2 is 1/256 of h's
    say(f"reference: Kahan–Li 8 at h = 1/400; own error ≈ {ref_err:.1e}; "
        f"|x_ref − DOP853(1e-13)| = {np.max(np.abs(x_dop - x_ref)):.1e}")

    def rhs(t, y):  # the user's call: NumPy right-hand side on (N,) arrays
        return np.concatenate((y[n:], acc(y[:n], **params)))

    runs: dict[str, list] = {name: [] for name in STEP_METHODS + RKN_METHODS + ("scipy-dop853", "compiled-dop853")}
    for name in STEP_METHODS:
        m = registry.method(name)
        per = max(m.traits.evals_per_step, 1.0)
        steps = int(t_end * 2)
        while steps * per <= 3e7:
            sec, x = _timed(lambda: final(name, steps), budget=0.3)
            err = float(np.max(np.abs(x - x_ref)))
            runs[name].append({"steps": steps, "seconds": sec, "error": err})
            if err < 1e-11:
                break
            steps = int(steps * 2 ** 0.5)
    ends = np.array([0.0, t_end])
    for name in RKN_METHODS:  # compiled RKN pairs, stepping onto t = T only
        m = registry.method(name, Options(progress=False))
        m.solve(system, x0, v0, np.array([0.0, 1.0]), 1e-6, 1e-9)
        for k in range(5, 27):
            rtol = 10.0 ** (-k / 2)
            sec, res = _timed(lambda: m.solve(system, x0, v0, ends, rtol, rtol * 1e-3), budget=0.3)
            err = float(np.max(np.abs(res.x[-1, :, 0] - x_ref)))
            runs[name].append({"rtol": rtol, "seconds": sec, "error": err})
            if err < 1e-11:
                break
    y0 = np.concatenate((x0, v0))
    for k in range(5, 27):
        rtol = 10.0 ** (-k / 2)
        sec, (x, *_rest) = _timed(lambda: dop853(system, x0, v0, t_end, rtol, rtol * 1e-3), budget=0.3)
        runs["compiled-dop853"].append({"rtol": rtol, "seconds": sec, "error": float(np.max(np.abs(x - x_ref)))})
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-3)
        sec = time.perf_counter() - t0
        runs["scipy-dop853"].append({"rtol": rtol, "seconds": sec, "evals": int(sol.nfev),
                                     "error": float(np.max(np.abs(sol.y[:n, -1] - x_ref)))})
        say(f"rtol {rtol:.0e}: compiled {runs['compiled-dop853'][-1]['seconds']:.3g} s, SciPy {sec:.3g} s, "
            f"error {runs['scipy-dop853'][-1]['error']:.1e}")
        if runs["scipy-dop853"][-1]["error"] < 1e-11 or sec > 60:
            break
    rows = []
    for accuracy in ACCURACIES:
        costs = {name: cost_at(rs, accuracy) for name, rs in runs.items()}
        ours = {n: c for n, c in costs.items() if n in STEP_METHODS + RKN_METHODS and c is not None}
        best = min(ours, key=ours.get) if ours else None
        row = {"accuracy": accuracy, "best": best, "best_seconds": ours.get(best),
               "scipy_dop853_seconds": costs["scipy-dop853"], "compiled_dop853_seconds": costs["compiled-dop853"]}
        for peer in ("scipy_dop853", "compiled_dop853"):
            row[f"vs_{peer}"] = (row[f"{peer}_seconds"] / row["best_seconds"]
                                 if best and row[f"{peer}_seconds"] else None)
        rows.append(row)
    return {"t_end": t_end, "reference_error": ref_err, "rows": rows, "runs": runs}


# -- 3. exact solution against the sin/cos floor -----------------------------------------------------
def exact_vs_floor(frames: int = 1001, budget: float = 3.0) -> dict:
    """The seed's exact solution (``modal``, S = ``frames`` times t = i·h) against ``np.cos``/``np.sin`` of
    the N·S phases, timed in turns (:func:`~numeric.bench.timing.interleaved_seconds`), three ways:

    * ``evaluation``: the method's run into a memory recorder on a system whose modes are computed (what
      every run after the first on a loaded system pays: solution from x0, v0 and its S frames);
    * ``with_setup``: the same on a fresh system, so also the accurate spectrum (the spring-factor SVD,
      rigid modes by structure) — once per system, as a compile is once per process for a step method;
    * ``api``: ``springchain.simulate(scene, ["modal"], progress=False)`` on the loaded scene, no files:
      also the module lookup, the grid checks, energies and the summary.
    """
    import springchain
    from springchain import _api
    from springchain.numeric.run import registry
    from springchain.numeric.run.grid import Grid
    from springchain.numeric.run.protocol import Options, record
    from springchain.numeric.bench.timing import interleaved_seconds

    scene = _api.load("seed")
    system, x0, v0 = _system("seed")
    grid = Grid(0.1, frames - 1, 1)
    method = registry.method("modal", Options(progress=False))
    w = np.sqrt(np.abs(system.module.omega2(**system.params)))[:, None]
    t = grid.t[None, :]

    def floor():
        ph = w * t
        return np.cos(ph), np.sin(ph)

    secs = interleaved_seconds({
        "floor": (floor, 1),
        "evaluation": (lambda: record(method, system, x0, v0, grid), 1),
        "with_setup": (lambda: record(method, system.fresh(), x0, v0, grid), 1),
        "api": (lambda: springchain.simulate(scene, ["modal"], steps=frames - 1, record_every=1, progress=False), 1),
    }, budget=budget, min_rounds=5)
    us = {k: 1e6 * v for k, v in secs.items()}
    return {"frames": frames, "sincos_floor_us": us["floor"], "evaluation_us": us["evaluation"],
            "with_setup_us": us["with_setup"], "api_us": us["api"],
            "ratio": us["evaluation"] / us["floor"], "ratio_with_setup": us["with_setup"] / us["floor"],
            "ratio_api": us["api"] / us["floor"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=1_000_000, help="Verlet steps on the seed (default 10^6)")
    ap.add_argument("--t-end", type=float, default=1000.0, help="Duffing horizon T (default 1000)")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    _report.add_option(ap)
    args = ap.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        from springchain.numeric.compiled.run import compile_seconds
        from springchain.numeric.bench.timing import single_threaded_blas

        import springchain.numeric.compiled.run as compiled_run

        compiled_run.COMPILE_MIN_EVALS = 0  # every run compiled: its compile is warm-up, reported separately
        say = (lambda *a: None) if args.json else print
        with single_threaded_blas():
            t0 = time.perf_counter()
            v = verlet_per_step(args.steps)
            say(f"1. Verlet on the seed, {v['steps']:.0e} steps, every 1000th recorded by both: springchain "
                f"{v['springchain_ns']:.1f} ns/step, hand-written numba {v['hand_numba_ns']:.1f} ns/step "
                f"(ratio {v['ratio']:.2f}; target ≤ 2); frames differ by {v['final_state_difference']:.1e} "
                f"(|x| up to {v['largest_position']:.1e})")
            e = exact_vs_floor()
            say(f"3. seed exact solution, S = {e['frames']}: sin/cos floor {e['sincos_floor_us']:.1f} µs; "
                f"evaluation {e['evaluation_us']:.0f} µs (ratio {e['ratio']:.1f}; target ≤ 3); "
                f"with the spectrum's set-up {e['with_setup_us']:.0f} µs ({e['ratio_with_setup']:.1f}); "
                f"springchain.simulate {e['api_us']:.0f} µs ({e['ratio_api']:.1f})")
            d = duffing(args.t_end, say)
            total = time.perf_counter() - t0
        say(f"2. Duffing, T = {d['t_end']:g}: seconds to reach each accuracy (error at t = T)")
        say("| accuracy | best springchain method | seconds | SciPy DOP853 (user's call) | × | compiled DOP853 | × |")
        say("|---|---|---|---|---|---|---|")

        def f(x, spec=".3g"):
            return "not reached" if x is None else format(x, spec)

        for r in d["rows"]:
            say(f"| {r['accuracy']:.0e} | {r['best'] or '—'} | {f(r['best_seconds'], '.2e')} | "
                f"{f(r['scipy_dop853_seconds'], '.2e')} | {f(r['vs_scipy_dop853'], '.0f')} | "
                f"{f(r['compiled_dop853_seconds'], '.2e')} | {f(r['vs_compiled_dop853'], '.1f')} |")
        say(f"compile (or disk-cache load) of the compiled loops: {compile_seconds():.1f} s, once, in no timing; "
            f"whole benchmark {total:.0f} s")
        if args.json:
            print(json.dumps({"verlet": v, "exact": e, "duffing": d, "compile_seconds": compile_seconds()}, indent=1))
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
