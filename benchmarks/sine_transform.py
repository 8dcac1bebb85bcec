"""What one orthonormal DST-I costs at a slow pocketfft length, by route, side by side.

Run ``python benchmarks/sine_transform.py [--n N] [--rounds R] [--json]``. In one process, in
interleaved rounds (BLAS and pocketfft pinned to one thread), it times on the same random vector

* ``pocketfft``: ``scipy.fft.dst(x, type=1, norm="ortho")`` at length N (the route before);
* ``chirp``: :func:`springchain.numeric.exact.sine_transform.dst1` at length N (the chirp-z convolution
  that a slow length takes; its chirp spectrum cached, as in a run that evaluates many frames);
* ``fast neighbour``: pocketfft at length N − 1 (``2N`` is 5-smooth for N = 10⁶), the floor;

and reports the median seconds and the largest difference between the two routes at length N
relative to ‖x‖ (the uniform chain's exact solution runs one transform per recorded frame).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402
import scipy.fft  # noqa: E402
import importlib.util
import sys
from pathlib import Path

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)


def measure(n: int, rounds: int) -> dict:
    from springchain.numeric.exact import sine_transform as stf

    x = np.random.default_rng(0).standard_normal(n)
    routes = {"pocketfft": lambda: scipy.fft.dst(x, type=1, norm="ortho", workers=1),
              "chirp": lambda: stf.dst1(x),
              "fast neighbour": lambda: scipy.fft.dst(x[:-1], type=1, norm="ortho", workers=1)}
    stf.dst1(x)  # the chirp spectrum of length n, cached once (a run reuses it for every frame)
    times: dict[str, list[float]] = {k: [] for k in routes}
    for _ in range(rounds):
        for name, call in routes.items():
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)
    err = float(np.max(np.abs(routes["pocketfft"]() - routes["chirp"]())) / np.linalg.norm(x))
    return {"n": n, "chirp_route": stf.uses_chirp(n), "rounds": rounds,
            "median_seconds": {k: statistics.median(v) for k, v in times.items()},
            "max_difference_over_norm": err}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=1_000_000, help="transform length (default 10^6)")
    p.add_argument("--rounds", type=int, default=5, help="interleaved rounds (default 5)")
    p.add_argument("--json", action="store_true", help="print JSON")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        r = measure(args.n, args.rounds)
        if args.json:
            print(json.dumps(r, indent=2))
            return 0
        print(f"DST-I, n = {r['n']} (chirp route: {r['chirp_route']}), median of {r['rounds']} interleaved rounds")
        for k, v in r["median_seconds"].items():
            print(f"  {k:<15s} {v:8.3f} s")
        print(f"  max |pocketfft - chirp| / ||x|| = {r['max_difference_over_norm']:.1e}")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
