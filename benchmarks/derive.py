"""Derivation benchmark: explicit ``[[springs]]`` chains against SymPy's ``LagrangesMethod``, and whole commands.

Run ``python benchmarks/derive.py [--sizes 10 40 80] [--command-sizes 40 80 200] [--repeats 3] [--json]``.

Two tables, all measured in one run:

* **Work** (:mod:`springchain.symbolic_cost`, one fresh process per case, imports
  excluded): the uniform free chain of N masses written as ``[masses]`` +
  ``[[springs]]`` (model, Euler–Lagrange equations, M and K, the normal modes
  with the closed-form search and its numeric fallback, the generated module)
  against ``LagrangesMethod`` on the same chain (equations, mass matrix,
  forcing). Target: ratio ≥ :data:`WORK_TARGET` at N = 40 and 80.
* **Whole commands**: wall and CPU seconds of a fresh ``springchain modes SCENE``
  and ``springchain derive SCENE`` on the same scenes (minimum over repeats,
  interleaved with a process that only imports SymPy). Target: ≤
  :data:`COMMAND_TARGET` s wall at N = 200.

Children run with ``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=1``. CPU seconds (user +
system of the child) are given beside wall seconds because on a shared machine the
wall time also measures the other processes.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from springchain import symbolic_cost
from springchain.symbolic_cost import Route
import importlib.util

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

#: Work ratio LagrangesMethod / [[springs]] required at N = 40 and 80.
WORK_TARGET = 10.0
#: Wall seconds allowed for a whole 200-mass command.
COMMAND_TARGET = 2.0
DEFAULT_SIZES = (10, 40, 80)
DEFAULT_COMMAND_SIZES = (40, 80, 200)


def _env() -> dict:
    env = symbolic_cost._python_env()
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", PYTHONDONTWRITEBYTECODE="1")
    return env


def _timed(argv: list[str], cwd: str, env: dict) -> tuple[float, float]:
    """(wall, CPU) seconds of one fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def work_table(sizes, progress) -> list[dict]:
    """Work seconds of both routes per N, the ratio and whether the target is met."""
    rows = []
    for n in sizes:
        el = symbolic_cost.measure(Route.ELEMENTS, n)
        progress(f"[[springs]] N = {n}: {el['total']:.3f} s of work (modes {el['modes']:.3f} s)")
        lag = symbolic_cost.measure(Route.LAGRANGE, n)
        lag_text = "over budget" if lag.get("total") is None else f"{lag['total']:.3f} s"
        progress(f"LagrangesMethod N = {n}: {lag_text} of work")
        ratio = None if lag.get("total") is None else lag["total"] / el["total"]
        rows.append({"n": n, "springs": el["total"], "springs_equations": el["equations"],
                     "springs_modes": el["modes"], "springs_codegen": el["codegen"],
                     "closed_form": el["closed_form"], "lagrange": lag.get("total"), "ratio": ratio,
                     "target": WORK_TARGET if n >= 40 else None,
                     "met": None if n < 40 or ratio is None else ratio >= WORK_TARGET})
    return rows


def command_table(sizes, repeats: int, progress) -> list[dict]:
    """Minimum wall and CPU seconds of fresh ``springchain modes`` / ``derive`` processes per N."""
    env = _env()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        env["SPRINGCHAIN_CACHE"] = str(Path(tmp) / "cache")
        for n in sizes:
            Path(tmp, f"cost{n}.toml").write_text(symbolic_cost.masses_scene_text(n), encoding="utf-8")
        cases = {"import sympy": ["-c", "import sympy"]}
        for n in sizes:
            cases[f"modes {n}"] = ["-m", "springchain", "modes", f"cost{n}.toml"]
            cases[f"derive {n}"] = ["-m", "springchain", "derive", f"cost{n}.toml", "--out", "gen"]
        best = {k: (float("inf"), float("inf")) for k in cases}
        for r in range(repeats):
            for label in list(cases)[r % len(cases):] + list(cases)[:r % len(cases)]:  # interleaved rounds
                wall, cpu = _timed(cases[label], tmp, env)
                best[label] = (min(best[label][0], wall), min(best[label][1], cpu))
        base = best["import sympy"]
        progress(f"import sympy: {base[0]:.2f} s wall, {base[1]:.2f} s CPU")
        for n in sizes:
            row = {"n": n, "sympy_import_wall": base[0], "sympy_import_cpu": base[1]}
            for cmd in ("modes", "derive"):
                wall, cpu = best[f"{cmd} {n}"]
                row[f"{cmd}_wall"], row[f"{cmd}_cpu"] = wall, cpu
                progress(f"springchain {cmd} cost{n}.toml: {wall:.2f} s wall, {cpu:.2f} s CPU")
            row["target"] = COMMAND_TARGET if n >= 200 else None
            row["met"] = None if n < 200 else max(row["modes_wall"], row["derive_wall"]) <= COMMAND_TARGET
            rows.append(row)
    return rows


def markdown(work: list[dict], commands: list[dict]) -> str:
    """The two tables as Markdown."""
    yes = {True: "yes", False: "**no**", None: "–"}
    lines = ["| N | `[[springs]]` work (s) | of which modes | `LagrangesMethod` work (s) | Lagrange / `[[springs]]` "
             f"| ≥ {WORK_TARGET:g}× |", "|---|---|---|---|---|---|"]
    for r in work:
        lag = "> budget" if r["lagrange"] is None else f"{r['lagrange']:.3g}"
        ratio = "–" if r["ratio"] is None else f"{r['ratio']:.1f}×"
        lines.append(f"| {r['n']} | {r['springs']:.3g} | {r['springs_modes']:.3g} | {lag} | {ratio} "
                     f"| {yes[r['met']]} |")
    if commands:
        base = commands[0]
        lines += ["", f"Whole command, fresh process (`python -c \"import sympy\"`: {base['sympy_import_wall']:.2f} s "
                      f"wall, {base['sympy_import_cpu']:.2f} s CPU):", "",
                  "| N | `modes` wall (s) | `modes` CPU (s) | `derive` wall (s) | `derive` CPU (s) "
                  f"| ≤ {COMMAND_TARGET:g} s |",
                  "|---|---|---|---|---|---|"]
        for r in commands:
            lines.append(f"| {r['n']} | {r['modes_wall']:.2f} | {r['modes_cpu']:.2f} | {r['derive_wall']:.2f} | "
                         f"{r['derive_cpu']:.2f} | {yes[r['met']]} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python benchmarks/derive.py", description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=list(DEFAULT_SIZES))
    parser.add_argument("--command-sizes", type=int, nargs="*", default=list(DEFAULT_COMMAND_SIZES))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", action="store_true")
    _report.add_option(parser)
    args = parser.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        say = (lambda line: None) if args.json else (lambda line: print(line, file=sys.stderr, flush=True))
        commands = command_table(args.command_sizes, max(args.repeats, 1), say) if args.command_sizes else []
        work = work_table(args.sizes, say)
        if args.json:
            print(json.dumps({"work": work, "commands": commands}, indent=1))
        else:
            print(markdown(work, commands), end="")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
