"""Throughput of `springchain sweep`: samples/second with 1 and 2 Dask workers against a plain loop.

A compute-bound sweep: disordered free-free chains (masses x uniform(0.5, 1.5)), each realisation
solved for every ω², mode participation ratio and transfer-matrix γ. The plain loop computes the same
realisations in this process (single-threaded BLAS, no Dask, no parquet); the Dask runs include
scattering the spec, the tasks and writing one parquet part per batch, but not the cluster's start
(workers are warmed up first). Samples per CPU-second (this process's CPU time for the loop, the
worker processes' for Dask) and the cores kept busy are reported too: on a shared machine they show
Dask's own overhead and the parallelism obtained, whatever the wall clock says. Targets: 2 workers >= 1.7x one worker, one worker within 10 % of the
plain loop.

    python benchmarks/sweep.py [--samples 400] [--n 2000] [--batch 10] [--json out.json]

Not a test: wall-clock numbers on a shared machine are noisy; run it on an idle one.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import tempfile
import time
from pathlib import Path
import importlib.util

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

SCENE = """
name = "benchchain{n}"
description = "sweep benchmark chain"
[parameters]
m = 1.0
k = 1.0
[chain]
n = {n}
mass = "m"
k = "k"
left = "free"
right = "free"
[initial]
x = "0"
v = "0"
[simulation]
dt = 0.1
steps = 10
"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=400)
    p.add_argument("--n", type=int, default=2000)
    p.add_argument("--batch", type=int, default=10)
    p.add_argument("--json", help="also write the numbers here")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):

        import springchain
        from dask.distributed import Client, LocalCluster

        from springchain._modules import load_module
        from springchain.numeric.sweep import driver as sweep_driver
        from springchain.numeric.sweep.distributions import parse
        from springchain.numeric.sweep.realisations import SweepSpec, compute_batch
        from springchain.numeric.bench.timing import single_threaded_blas

        tmp = Path(tempfile.mkdtemp(prefix="sweep-bench-"))
        scene_path = tmp / "chain.toml"
        scene_path.write_text(SCENE.format(n=args.n), encoding="utf-8")
        sc = springchain.load(scene_path)
        module, _ = load_module(sc)
        spec = SweepSpec(sc.name, Path(module.__file__).read_text(encoding="utf-8"), tuple(sorted(sc.parameters.items())),
                         (), (("mass", parse("uniform(0.5, 1.5)")),), args.samples, 0)
        say = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
        results = {"samples": args.samples, "n": args.n, "batch": args.batch, "cpus": os.cpu_count()}

        with single_threaded_blas():
            compute_batch(spec, 0, 1)  # warm-up
            t0, c0 = time.perf_counter(), time.process_time()
            for a, b in ((s, min(s + args.batch, spec.total)) for s in range(0, spec.total, args.batch)):
                compute_batch(spec, a, b)
            results["plain_loop"] = spec.total / (time.perf_counter() - t0)
            results["plain_loop_per_cpu_s"] = spec.total / (time.process_time() - c0)
        say(f"plain loop: {results['plain_loop']:.3g} samples/s, {results['plain_loop_per_cpu_s']:.3g} per CPU-s")

        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                              silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
                client.run(lambda: compute_batch(spec, 0, 1))  # warm-up: imports, module exec
                out = tmp / f"w{workers}"
                out.mkdir()
                cpu0 = sum(client.run(time.process_time).values())
                t0 = time.perf_counter()
                sweep_driver.run(spec, out, args.batch, client, progress=False)
                wall = time.perf_counter() - t0
                cpu = sum(client.run(time.process_time).values()) - cpu0
                results[f"dask_{workers}"] = spec.total / wall
                results[f"dask_{workers}_per_cpu_s"] = spec.total / cpu  # worker processes' CPU time
                results[f"dask_{workers}_cores_used"] = cpu / wall
            say(f"dask, {workers} worker(s): {results[f'dask_{workers}']:.3g} samples/s, "
                f"{results[f'dask_{workers}_per_cpu_s']:.3g} per worker CPU-s, {cpu / wall:.2f} cores busy")

        results["speedup_2_over_1"] = results["dask_2"] / results["dask_1"]
        results["dask_1_over_plain"] = results["dask_1"] / results["plain_loop"]
        results["load_average"] = os.getloadavg()
        print(f"| run | samples/s (wall) | samples per CPU-second | cores busy |\n|---|---|---|---|\n"
              f"| plain loop (in-process) | {results['plain_loop']:.3g} | {results['plain_loop_per_cpu_s']:.3g} | - |\n"
              f"| Dask, 1 worker | {results['dask_1']:.3g} | {results['dask_1_per_cpu_s']:.3g} | "
              f"{results['dask_1_cores_used']:.2f} |\n"
              f"| Dask, 2 workers | {results['dask_2']:.3g} | {results['dask_2_per_cpu_s']:.3g} | "
              f"{results['dask_2_cores_used']:.2f} |\n\n"
              f"2 workers / 1 worker = {results['speedup_2_over_1']:.2f} (target >= 1.7); "
              f"1 worker / plain loop = {results['dask_1_over_plain']:.2f} (target >= 0.90); "
              f"load average {results['load_average'][0]:.2f} on {os.cpu_count()} CPUs")
        if args.json:
            Path(args.json).write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
