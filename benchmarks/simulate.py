"""What ``springchain simulate`` costs per step on a long ``[chain]`` scene, beside the memory floor.

Run ``python benchmarks/simulate.py [--n N] [--rounds R] [--json]``. In one process, in
interleaved rounds, it times

* ``springchain.simulate(scene, methods=["verlet"], steps=S)`` — the very call behind the
  command — at two run lengths S₁ < S₂ (recording only the first and last frame), so the
  per-step cost ``(t(S₂) − t(S₁)) / (S₂ − S₁)`` has set-up, loading and writing cancelled;
* the 32-byte-per-mass floor: one in-place pass ``x ← x + c·v, v ← v − c·x`` over two N-arrays
  (:func:`springchain.numeric.compiled.fast.stream_update`) and a NumPy copy of 2N doubles; the faster.

for a uniform chain (the bundled ``chain100k`` at N masses) and an index-dependent one. BLAS is
pinned to one thread. Targets (issue 13): uniform ≤ 1.5× the floor, index-dependent ≤ 2.5×.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import importlib.util
import sys

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

TARGETS = {"uniform": 1.5, "index-dependent": 2.5}


def _scenes(n: int, folder: Path) -> dict[str, Path]:
    from springchain._scenes import bundled_scene_dir

    text = (bundled_scene_dir() / "chain100k.toml").read_text(encoding="utf-8")
    lines = []
    for line in text.splitlines():
        if line.startswith("n ="):
            line = f"n = {n}"
        elif line.startswith("name ="):
            line = 'name = "bench_uniform"'
        lines.append(line)
    uniform = folder / "bench_uniform.toml"
    uniform.write_text("\n".join(lines) + "\n", encoding="utf-8")
    from springchain.symbolic_cost import RANDOM_K, RANDOM_MASS, chain_scene_text

    dependent = folder / "bench_dependent.toml"
    dependent.write_text(chain_scene_text(n, mass=RANDOM_MASS, k=RANDOM_K, name="bench_dependent"),
                         encoding="utf-8")
    return {"uniform": uniform, "index-dependent": dependent}


def measure(n: int = 1_000_000, rounds: int = 5, short: int = 200, long: int = 2200) -> dict:
    """Per-step seconds of ``simulate`` and the floor, median and minimum over interleaved rounds."""
    from springchain import _api
    from springchain.numeric.compiled import fast
    from springchain.numeric.bench.timing import single_threaded_blas

    out: dict = {"n": n, "rounds": rounds, "steps": [short, long], "numba": fast.available()}
    with tempfile.TemporaryDirectory() as tmp, single_threaded_blas():
        tmp = Path(tmp)
        scenes = {k: _api.load(p) for k, p in _scenes(n, tmp).items()}

        def run(scene, steps):
            t0 = time.perf_counter()
            _api.simulate(scene, methods=["verlet"], steps=steps, record_every=steps, out=tmp / "out")
            return time.perf_counter() - t0

        for scene in scenes.values():  # warm-up: derive into the cache, compile the kernels
            run(scene, 2)
        x, v = np.random.default_rng(0).standard_normal((2, n))
        src, dst = np.random.default_rng(1).standard_normal(2 * n), np.empty(2 * n)

        def floor():
            reps = 20
            t0 = time.perf_counter()
            for _ in range(reps):
                fast.stream_update(x, v)
            stream = (time.perf_counter() - t0) / reps
            t0 = time.perf_counter()
            for _ in range(reps):
                np.copyto(dst, src)
            return min(stream, (time.perf_counter() - t0) / reps)

        samples: dict[str, list[float]] = {k: [] for k in scenes} | {"floor": []}
        ratios: dict[str, list[float]] = {k: [] for k in scenes}
        for _ in range(rounds):
            fl = floor()
            samples["floor"].append(fl)
            for name, scene in scenes.items():
                per_step = (run(scene, long) - run(scene, short)) / (long - short)
                samples[name].append(per_step)
                ratios[name].append(per_step / fl)
    out["ns_per_mass"] = {k: {"median": statistics.median(s) / n * 1e9, "min": min(s) / n * 1e9}
                          for k, s in samples.items()}
    out["over_floor"] = {k: {"median": statistics.median(r), "limit": TARGETS[k],
                             "met": statistics.median(r) <= TARGETS[k]} for k, r in ratios.items()}
    return out


def markdown(result: dict) -> str:
    lines = [f"N = {result['n']:,} masses, {result['rounds']} interleaved rounds, per step from "
             f"{result['steps'][0]} and {result['steps'][1]} steps (numba: {result['numba']})", "",
             "| what | ns/mass/step (median) | min | / floor (median of per-round ratios) | target |",
             "|---|---:|---:|---:|---:|"]
    for k, row in result["ns_per_mass"].items():
        ratio = result["over_floor"].get(k)
        tail = (f"{ratio['median']:.2f}× | ≤ {ratio['limit']:g}× " + ("met" if ratio["met"] else "MISSED")
                if ratio else "1 | —")
        label = "32-byte floor" if k == "floor" else f"`simulate` verlet, {k} chain"
        lines.append(f"| {label} | {row['median']:.3f} | {row['min']:.3f} | {tail} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python benchmarks/simulate.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=1_000_000, help="masses (default: %(default)s)")
    p.add_argument("--rounds", type=int, default=5, help="interleaved rounds (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a Markdown table")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        result = measure(args.n, max(1, args.rounds))
        print(json.dumps(result, indent=1) if args.json else markdown(result), end="" if not args.json else "\n")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
