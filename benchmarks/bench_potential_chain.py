"""The fused kernel of a nonlinear chain (a potential compiled from its expression) beside the linear one.

Run ``python benchmarks/bench_potential_chain.py [--n N] [--steps S] [--rounds R] [--json]``.

Two ``[chain]`` scenes of N = 10⁶ equal masses between walls, written here as TOML and derived
like any user scene: the linear chain (``k = "k"``) and the FPUT-β chain
(``potential = "k*d**2/2 + beta*d**4/4"``). Each runs velocity Verlet through
:class:`springchain.numeric.compiled.fast.FusedVerlet` (numba; ``advance``, the two-steps-per-sweep
half-step form every long Verlet run uses), S steps per call, the two interleaved for R rounds in
one process with BLAS pinned to one thread; per-step time = the minimum over rounds / S. The FPUT-β
kernel calls the tension ``V'(d) = k d + β d³`` that numba compiled from the generated module's
``spring_force``. Target (issue 21): FPUT-β ≤ 2 × linear per step. Memory stays bounded: three
float64 arrays of N (x, v, a), 24 MB at N = 10⁶, for either chain.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import importlib.util

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

TARGET = 2.0

SCENES = {
    "linear": ('k = "k"', "k = 1.0"),
    "fput_beta": ('potential = "k*d**2/2 + beta*d**4/4"', "k = 1.0\nbeta = 1.0"),
}


def _scene_text(name: str, n: int, law: str, params: str) -> str:
    return (f'name = "bench_{name}"\n[parameters]\nm = 1.0\n{params}\n[chain]\nn = {n}\nmass = "m"\n{law}\n'
            'left = "wall"\nright = "wall"\n[initial]\nx = "0.3*sin(pi*(i + 1)/(n + 1))"\n')


def measure(n: int = 10**6, steps: int = 20, rounds: int = 7, h: float = 0.1) -> dict:
    import springchain as sc
    from springchain._modules import load_module
    from springchain.numeric.compiled.fast import Backend, FusedVerlet
    from springchain.numeric.bench.timing import single_threaded_blas

    kernels, states = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (law, params) in SCENES.items():
            path = Path(tmp) / f"{name}.toml"
            path.write_text(_scene_text(name, n, law, params))
            scene = sc.load(path)
            module, _ = load_module(scene)
            t0 = time.perf_counter()
            fv = FusedVerlet.from_module(module, None, n, h, Backend.NUMBA)
            x = scene.x0.copy()
            v = np.zeros(n)
            a = fv.force(x)
            fv.advance(x, v, a, 2)  # compile (or load) and warm up
            kernels[name] = fv
            states[name] = (x, v, a)
            print(f"{name}: ready in {time.perf_counter() - t0:.1f} s (derive, load, compile)", file=sys.stderr)
    samples = {name: [] for name in kernels}
    with single_threaded_blas():
        for _ in range(rounds):
            for name, fv in kernels.items():
                x, v, a = states[name]
                t0 = time.perf_counter()
                fv.advance(x, v, a, steps)
                samples[name].append((time.perf_counter() - t0) / steps)
    per_step = {name: min(s) for name, s in samples.items()}
    ratio = per_step["fput_beta"] / per_step["linear"]
    return {"n": n, "steps_per_call": steps, "rounds": rounds, "h": h,
            "seconds_per_step": per_step, "median_seconds_per_step": {k: float(np.median(s)) for k, s in samples.items()},
            "ns_per_mass_step": {k: 1e9 * s / n for k, s in per_step.items()},
            "ratio": ratio, "target": TARGET, "met": ratio <= TARGET,
            "memory_bytes_per_mass": 24}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=10**6)
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--json", action="store_true")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        r = measure(args.n, args.steps, args.rounds)
        if args.json:
            print(json.dumps(r, indent=2))
            return 0
        print(f"N = {r['n']}, {r['steps_per_call']} steps per call, min of {r['rounds']} interleaved rounds, one thread")
        for name, s in r["seconds_per_step"].items():
            print(f"  {name:10s} {s * 1e3:8.3f} ms per step  ({r['ns_per_mass_step'][name]:.2f} ns per mass and step)")
        print(f"  FPUT-beta / linear = {r['ratio']:.2f}  (target <= {TARGET:g}: {'met' if r['met'] else 'NOT met'})")
        return 0


if __name__ == "__main__":
    sys.exit(main())
