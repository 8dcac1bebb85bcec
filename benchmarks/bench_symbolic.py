"""The symbolic side in bounded time: ``modes``, ``frf``, ``plan``, ``derive`` and the exact solution's set-up.

Run ``python benchmarks/bench_symbolic.py [--only NAME ...] [--timeout 120] [--skip-derive] [--skip-exact]
[--json] [--markdown FILE]``. In one run, side by side:

1. **The corpus** (``benchmarks/corpus/*.toml``, written by ``benchmarks/corpus/generate.py``): scenes of 2
   to 40 masses with NAMED parameters, distinct per mass and spring, covering every element kind. Each
   scene runs ``springchain modes SCENE``, ``modes --json`` and (every scene) ``frf --points 200`` from the
   first mass to the last, each in a fresh process that first imports what the commands use (SymPy,
   NumPy, SciPy, matplotlib, springchain) and then times only the command (``cli.main``): seconds of work
   after imports. A case running past ``--timeout`` is stopped and shown as ``> T``. Targets: ``modes``
   ≤ 3 s for ≤ 12 masses and ≤ 10 s for ≤ 40; ``modes --json`` ≤ 1.2 × text; ``frf`` ≤ 2 s for ≤ 12 masses.
   Each scene's line also says which parts were closed-form (the ``closed form:`` line of ``modes``).
2. **``sc.plan("seed", 1e-6)``**: seconds of work after imports, fresh process. Target ≤ 3 s.
3. **``derive`` against SymPy's ``LagrangesMethod``**: whole command (``python -m springchain derive
   SCENE``) against a whole script (``python -c "…LagrangesMethod…"``: import, equations, mass matrix and
   forcing) on the same 40-mass chain, each a fresh process, interleaved rounds, minimum wall and CPU
   seconds. Target ≥ 10×.
4. **The reference scene's exact solution with its set-up** against the sin/cos floor (S = 1001), as in
   ``bench_small.py``. Target ≤ 3×.

Children run with ``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=MKL_NUM_THREADS=1`` (one BLAS thread, as every
benchmark here); the machine's load average is printed with the results (on a shared machine compare the
ratios of one run, not seconds across runs).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

HERE = Path(__file__).resolve().parent
CORPUS = HERE / "corpus"

#: Targets (seconds of work after imports, and ratios).
MODES_SMALL, MODES_LARGE, SMALL_N, LARGE_N = 3.0, 10.0, 12, 40
JSON_OVER_TEXT = 1.2
FRF_SECONDS, FRF_POINTS = 2.0, 200
PLAN_SECONDS = 3.0
DERIVE_RATIO = 10.0
EXACT_RATIO = 3.0
DERIVE_N = 40


def _env() -> dict:
    env = dict(os.environ)
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", MPLBACKEND="Agg")
    return env


# -- children: one case each, imports first, then the timed work ----------------------------------------
def _child(kind: str, args: list[str]) -> None:
    """Run one case in this (fresh) process and print one JSON line: {"seconds": work, ...}."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401 - frf's figure: an import, not work
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    import sympy  # noqa: F401

    import springchain
    from springchain import cli

    out = {}
    if kind == "plan":
        t0 = time.perf_counter()
        springchain.plan(args[0], float(args[1]))
        out["seconds"] = time.perf_counter() - t0
    else:
        buf = io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(buf):
            code = cli.main(args)
        out["seconds"] = time.perf_counter() - t0
        out["code"] = code
        if kind == "modes":
            text = buf.getvalue()
            line = next((ln for ln in text.splitlines() if ln.startswith("closed form:")), "")
            out["closed_form"] = line.removeprefix("closed form:").strip()
    print(json.dumps(out))


def _run_child(kind: str, args: list[str], timeout: float) -> dict:
    """One fresh process of :func:`_child`; {"seconds": None, "timeout": True} past ``timeout``."""
    t0 = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, __file__, "--child", kind, *args], capture_output=True, text=True,
                              timeout=timeout, env=_env(), cwd=tempfile.gettempdir())
    except subprocess.TimeoutExpired:
        return {"seconds": None, "timeout": True, "wall": time.perf_counter() - t0}
    if done.returncode != 0 or not done.stdout.strip():
        return {"seconds": None, "error": (done.stderr.strip().splitlines() or ["?"])[-1][:200]}
    out = json.loads(done.stdout.strip().splitlines()[-1])
    if out.get("code"):
        out["error"] = f"exit status {out['code']}: " + (done.stderr.strip().splitlines() or ["?"])[-1][:200]
    return out


def corpus_scenes(only: list[str] | None = None) -> list[tuple[str, Path, int, list[str]]]:
    """(name, path, masses, mass names) of the corpus, sorted by size then name."""
    import tomllib

    out = []
    for path in sorted(CORPUS.glob("*.toml")):
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        names = list(data["masses"])
        if only and path.stem not in only:
            continue
        out.append((path.stem, path, len(names), names))
    return sorted(out, key=lambda r: (r[2], r[0]))


def corpus_table(scenes, timeout: float, say) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as figs:
        for name, path, n, masses in scenes:
            row = {"scene": name, "n": n}
            text = _run_child("modes", ["modes", str(path)], timeout)
            js = _run_child("json", ["modes", "--json", str(path)], timeout)
            frf = _run_child("frf", ["frf", str(path), "--input", masses[0], "--output", masses[-1],
                                     "--points", str(FRF_POINTS), "--out", figs], timeout)
            row |= {"modes": text.get("seconds"), "json": js.get("seconds"), "frf": frf.get("seconds"),
                    "closed_form": text.get("closed_form", ""),
                    "errors": {k: r["error"] for k, r in (("modes", text), ("json", js), ("frf", frf)) if r.get("error")}}
            rows.append(row)
            say(f"{name:<14} N = {n:>2}: modes {_s(row['modes'], timeout)}, --json {_s(row['json'], timeout)}, "
                f"frf {_s(row['frf'], timeout)}" + (f"  ERRORS {row['errors']}" if row["errors"] else ""))
    return rows


def _s(x, timeout=None) -> str:
    return f"> {timeout:g}" if x is None and timeout else ("–" if x is None else f"{x:.2f}")


def _limit(n: int) -> float:
    return MODES_SMALL if n <= SMALL_N else MODES_LARGE


# -- derive against LagrangesMethod ----------------------------------------------------------------------
LAGRANGE_SCRIPT = """
import sympy as sp
from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols
n = {n}
t = dynamicsymbols._t
q = dynamicsymbols(f"q0:{{n}}")
m, k = sp.symbols("m k", positive=True)
T = sum((m * qi.diff(t) ** 2 / 2 for qi in q), sp.Integer(0))
V = sum((k * (q[i + 1] - q[i]) ** 2 / 2 for i in range(n - 1)), sp.Integer(0))
lm = LagrangesMethod(T - V, q)
lm.form_lagranges_equations()
lm.mass_matrix, lm.forcing
"""


def _timed(argv: list[str], cwd: str) -> tuple[float, float]:
    """(wall, CPU) seconds of one fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], cwd=cwd, env=_env(), check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def derive_ratio(n: int, repeats: int, say) -> dict:
    """Whole ``springchain derive`` of the free [masses]+[[springs]] chain of n equal masses against a whole
    LagrangesMethod script on the same chain: minimum wall and CPU seconds over interleaved rounds."""
    from springchain import symbolic_cost

    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, f"cost{n}.toml").write_text(symbolic_cost.masses_scene_text(n), encoding="utf-8")
        env_cache = str(Path(tmp) / "cache")
        os.environ["SPRINGCHAIN_CACHE"] = env_cache  # the children's cache: inside the run's folder
        cases = {"derive": ["-m", "springchain", "derive", f"cost{n}.toml", "--out", "gen"],
                 "lagrange": ["-c", LAGRANGE_SCRIPT.format(n=n)],
                 "import sympy": ["-c", "import sympy"]}
        best = {k: [float("inf"), float("inf")] for k in cases}
        for r in range(repeats):
            for label in list(cases)[r % 3:] + list(cases)[:r % 3]:
                wall, cpu = _timed(cases[label], tmp)
                best[label] = [min(best[label][0], wall), min(best[label][1], cpu)]
        os.environ.pop("SPRINGCHAIN_CACHE", None)
    out = {"n": n, **{f"{k.replace(' ', '_')}_{w}": best[k][i] for k in cases for i, w in enumerate(("wall", "cpu"))}}
    out["ratio_wall"] = best["lagrange"][0] / best["derive"][0]
    out["ratio_cpu"] = best["lagrange"][1] / best["derive"][1]
    say(f"derive N = {n}: {best['derive'][0]:.2f} s wall ({best['derive'][1]:.2f} CPU); LagrangesMethod script "
        f"{best['lagrange'][0]:.2f} s wall ({best['lagrange'][1]:.2f} CPU): {out['ratio_wall']:.1f}× wall, "
        f"{out['ratio_cpu']:.1f}× CPU")
    return out


def exact_ratio() -> dict:
    """bench_small.py's exact solution against the sin/cos floor (evaluation, with set-up, API)."""
    spec = importlib.util.spec_from_file_location("springchain_benchmarks_bench_small", HERE / "bench_small.py")
    small = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(small)
    from springchain.numeric.bench.timing import single_threaded_blas

    with single_threaded_blas():
        return small.exact_vs_floor()


def _plan(timeout: float) -> dict:
    return _run_child("plan", ["seed", "1e-6"], timeout)


# -- report ----------------------------------------------------------------------------------------------
def markdown(rows: list[dict], timeout: float) -> str:
    yes = {True: "yes", False: "**no**"}
    lines = ["| scene | N | `modes` (s) | `modes --json` (s) | json / text | `frf` (s) | within targets | closed form |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ratio = r["json"] / r["modes"] if r["json"] and r["modes"] else None
        lines.append(f"| {r['scene']} | {r['n']} | {_s(r['modes'], timeout)} | {_s(r['json'], timeout)} | "
                     f"{'–' if ratio is None else f'{ratio:.2f}'} | {_s(r['frf'], timeout)} | {yes[_met(r)]} | "
                     f"{r['closed_form'] or '–'} |")
    lines += ["", "| masses | scenes | `modes` median (s) | `modes` worst (s) | worst scene | `--json` worst (s) "
                  "| `frf` median (s) | `frf` worst (s) |", "|---|---|---|---|---|---|---|---|"]
    for lo, hi in ((2, 3), (4, 6), (8, 12), (13, 20), (21, 40)):
        group = [r for r in rows if lo <= r["n"] <= hi]
        if not group:
            continue

        def big(x):
            return float("inf") if x is None else x

        worst = max(group, key=lambda r: big(r["modes"]))
        med = statistics.median(big(r["modes"]) for r in group)
        fmed = statistics.median(big(r["frf"]) for r in group)
        lines.append(f"| {lo}–{hi} | {len(group)} | {_s(med if med != float('inf') else None, timeout)} | "
                     f"{_s(worst['modes'], timeout)} | {worst['scene']} | "
                     f"{_s(max((big(r['json']) for r in group)) if all(r['json'] for r in group) else None, timeout)} | "
                     f"{_s(fmed if fmed != float('inf') else None, timeout)} | "
                     f"{_s(max(big(r['frf']) for r in group) if all(r['frf'] for r in group) else None, timeout)} |")
    return "\n".join(lines) + "\n"


def _met(r: dict) -> bool:
    ok = r["modes"] is not None and r["modes"] <= _limit(r["n"])
    ok &= r["json"] is not None and r["modes"] is not None and r["json"] <= JSON_OVER_TEXT * r["modes"] + 0.05
    if r["n"] <= SMALL_N:
        ok &= r["frf"] is not None and r["frf"] <= FRF_SECONDS
    return bool(ok and not r["errors"])


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--child"]:
        _child(argv[1], argv[2:])
        return 0
    parser = argparse.ArgumentParser(prog="python benchmarks/bench_symbolic.py", description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="*", help="corpus scenes to run (file stems; default: all)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds one case may run (default 120)")
    parser.add_argument("--repeats", type=int, default=3, help="rounds of the derive comparison (default 3)")
    parser.add_argument("--skip-corpus", action="store_true")
    parser.add_argument("--skip-derive", action="store_true")
    parser.add_argument("--skip-exact", action="store_true")
    parser.add_argument("--json", action="store_true")
    _report.add_option(parser)
    args = parser.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        say = (lambda line: None) if args.json else (lambda line: print(line, file=sys.stderr, flush=True))
        load = os.getloadavg()[0]
        result = {"load_before": load}
        if not args.skip_corpus:
            result["corpus"] = corpus_table(corpus_scenes(args.only), args.timeout, say)
            result["plan"] = _plan(args.timeout)
            say(f"plan seed: {_s(result['plan'].get('seconds'), args.timeout)} s")
        if not args.skip_derive:
            result["derive"] = derive_ratio(DERIVE_N, max(args.repeats, 1), say)
        if not args.skip_exact:
            result["exact"] = exact_ratio()
        result["load_after"] = os.getloadavg()[0]
        if args.json:
            print(json.dumps(result, indent=1))
            return 0
        print(f"load average: {result['load_before']:.2f} before, {result['load_after']:.2f} after "
              "(2 cores; seconds are inflated by the load, ratios of one run compare)")
        if "corpus" in result:
            rows = result["corpus"]
            print(f"Corpus: {len(rows)} scenes, seconds of work after imports (fresh process each; "
                  f"> {args.timeout:g}: stopped)")
            print()
            print(markdown(rows, args.timeout), end="")
            print()
            small = [r for r in rows if r["n"] <= SMALL_N]

            def worst(key, group):
                vals = [r[key] for r in group]
                return None if any(v is None for v in vals) or not vals else max(vals)

            jr = [r["json"] / r["modes"] for r in rows if r["json"] and r["modes"]]
            p = result["plan"].get("seconds")
            print(f"worst modes, <= {SMALL_N} masses: {_s(worst('modes', small), args.timeout)} s (target <= "
                  f"{MODES_SMALL:g}); <= {LARGE_N}: {_s(worst('modes', rows), args.timeout)} s (target <= "
                  f"{MODES_LARGE:g}); worst --json / text {max(jr, default=float('nan')):.2f} (target <= "
                  f"{JSON_OVER_TEXT:g}); worst frf, <= {SMALL_N} masses at {FRF_POINTS} points: "
                  f"{_s(worst('frf', small), args.timeout)} s (target <= {FRF_SECONDS:g}); "
                  f"plan('seed', 1e-6): {_s(p, args.timeout)} s (target <= {PLAN_SECONDS:g}); "
                  f"scenes within every target: {sum(_met(r) for r in rows)} of {len(rows)}")
        if "derive" in result:
            d = result["derive"]
            print(f"derive, {d['n']}-mass [masses]+[[springs]] chain, whole command: {d['derive_wall']:.2f} s wall "
                  f"({d['derive_cpu']:.2f} s CPU); LagrangesMethod whole script {d['lagrange_wall']:.2f} s wall "
                  f"({d['lagrange_cpu']:.2f} s CPU); python -c 'import sympy' {d['import_sympy_wall']:.2f} s wall: "
                  f"ratio {d['ratio_wall']:.1f}× wall, {d['ratio_cpu']:.1f}× CPU (target >= {DERIVE_RATIO:g}×)")
        if "exact" in result:
            e = result["exact"]
            print(f"seed exact solution, S = {e['frames']}: sin/cos floor {e['sincos_floor_us']:.1f} µs; evaluation "
                  f"{e['evaluation_us']:.0f} µs ({e['ratio']:.1f}×); with its set-up {e['with_setup_us']:.0f} µs "
                  f"({e['ratio_with_setup']:.1f}×, target <= {EXACT_RATIO:g}×); springchain.simulate "
                  f"{e['api_us']:.0f} µs ({e['ratio_api']:.1f}×)")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
