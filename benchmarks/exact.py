"""The exact modal solution's cost beside the trigonometry it cannot avoid.

Run ``python benchmarks/exact.py [--json]``. On the reference scene (S = 1001 output
times, N = 3) it times, interleaved, the exact solution as ``simulate`` computes it (modal
coordinates from the initial state, then positions and velocities at every output time) and
NumPy evaluating the S × N cosine/sine pairs alone (``np.cos`` and ``np.sin`` of the phase
array). Target (issue 13): exact ≤ 3 × trigonometry.
"""

from __future__ import annotations

import argparse
import json
import statistics
import timeit

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

TARGET = 3.0


def measure(scene: str = "seed", rounds: int = 7, number: int = 200) -> dict:
    from springchain import _api
    from springchain._modules import system_of
    from springchain.numeric.exact.modal import ModalSolution
    from springchain.numeric.run.grid import Grid

    sc = _api.load(scene)
    system, _ = system_of(sc)
    spec = system.spectrum
    t = Grid(sc.dt * sc.record_every, sc.steps // sc.record_every).t
    phase = np.multiply.outer(t, spec.omega)

    def exact():
        return ModalSolution.from_initial(spec, sc.x0, sc.v0).at(t)

    def trig():
        return np.cos(phase), np.sin(phase)

    from springchain.numeric.bench.timing import single_threaded_blas

    samples = {"exact": [], "trig": []}
    with single_threaded_blas():  # one BLAS thread, as every benchmark here
        for _ in range(rounds):
            for name, f in (("exact", exact), ("trig", trig)):
                samples[name].append(timeit.timeit(f, number=number) / number)
    ratios = [e / g for e, g in zip(samples["exact"], samples["trig"])]
    return {"scene": sc.name, "S": int(t.shape[0]), "N": int(system.n),
            "seconds": {k: {"median": statistics.median(v), "min": min(v)} for k, v in samples.items()},
            "ratio_median": statistics.median(ratios), "limit": TARGET,
            "met": statistics.median(ratios) <= TARGET}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python benchmarks/exact.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print JSON")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        r = measure()
        if args.json:
            print(json.dumps(r, indent=1))
        else:
            s = r["seconds"]
            print(f"{r['scene']}: S = {r['S']} times, N = {r['N']} masses\n"
                  f"  exact solution   {s['exact']['median'] * 1e6:8.1f} µs (min {s['exact']['min'] * 1e6:.1f})\n"
                  f"  cos + sin alone  {s['trig']['median'] * 1e6:8.1f} µs (min {s['trig']['min'] * 1e6:.1f})\n"
                  f"  ratio {r['ratio_median']:.2f}× (median of per-round ratios), target ≤ {TARGET:g}× — "
                  + ("met" if r["met"] else "MISSED"))
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
