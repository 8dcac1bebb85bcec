"""The cost of mode sensitivities (∂ω²/∂p and ∂φ/∂p by Nelson's method) per mode and parameter.

Run ``python benchmarks/bench_sensitivity.py [--json] [--n N] [--modes J] [--markdown FILE]``, BLAS pinned to
one thread:

* a **40-mass** ``[masses]`` scene (masses and springs over 12 decades, four parameters, every mode):
  the dense route (spring-factor SVD refined to double-double, Nelson through the modal corrector);
* a **10⁵-mass** open ``[chain]`` (index-dependent masses and springs, two parameters, the J lowest and J
  highest modes): the O(n) route (bisection, twisted factorisation, Nelson's tridiagonal system).

Each is timed after one warm-up evaluation (imports, the generated module, the symbolic element
derivatives are set-up, reported apart), as the best of ``--repeat`` runs, and divided by modes ×
parameters. The set-up time (the spectrum of the dense scene is O(N³), a chain's bisection O(n) per mode)
is inside the timed call.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)


def dense_scene(n: int = 40, seed: int = 0) -> str:
    """A 40-mass scene: a chain with walls and a few cross springs, elements c·p over 12 decades."""
    rng = np.random.default_rng(seed)
    params = {"ma": 1.0, "mb": 1e6, "ka": 1.0, "kb": 1e6}
    lines = ['name = "dense40"', 'description = "40 masses, masses and springs over 12 decades"', "",
             "[parameters]"] + [f"{k} = {v!r}" for k, v in params.items()] + ["", "[masses]"]
    lines += [f'x{i} = "{float(10 ** rng.uniform(-3, 3))!r}*{"ma" if i % 2 else "mb"}"' for i in range(n)]
    springs = [("wall", "x0")] + [(f"x{i}", f"x{i + 1}") for i in range(n - 1)] + [(f"x{n - 1}", "wall")]
    springs += [(f"x{i}", f"x{(i + 7) % n}") for i in range(0, n, 5)]
    for j, (a, b) in enumerate(springs):
        lines += ["", "[[springs]]", f'between = ["{a}", "{b}"]',
                  f'k = "{float(10 ** rng.uniform(-3, 3))!r}*{"ka" if j % 3 else "kb"}"']
    return "\n".join(lines) + "\n"


def chain_scene(n: int) -> str:
    return (f'name = "chain_sens"\ndescription = "index-dependent open chain"\n\n[parameters]\nm = 1.0\nk = 1.0\n'
            f'a = 0.5\n\n[chain]\nn = {n}\nmass = "m*(1 + a*(i % 3))"\nk = "k*(2 + sin(i))"\nleft = "wall"\n'
            f'right = "free"\n')


def timed(setup, wanted, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        setup.at(None, wanted)
        best = min(best, time.perf_counter() - t0)
    return best


def measure(text: str, wanted, repeat: int, folder: Path) -> dict:
    import springchain as sc
    from springchain._sensitivity import Setup

    path = folder / "scene.toml"
    path.write_text(text)
    t0 = time.perf_counter()
    setup = Setup(sc.load(path), None, closed_forms=False)
    set_up = time.perf_counter() - t0
    r = setup.at(None, wanted)  # warm-up
    seconds = timed(setup, wanted, repeat)
    J, P = r.index.shape[0], len(r.parameters)
    return {"masses": int(r.shapes.shape[0]), "modes": J, "parameters": P, "set_up_seconds": set_up,
            "seconds": seconds, "per_mode_and_parameter": seconds / (J * P), "route": r.route,
            "worst_settled": float(np.max(r.settled))}


def _print(out: dict, n: int) -> None:
    """The Markdown table of the text output (one row per scene)."""
    print(f"Sensitivities of every listed mode to every parameter; best of the timed runs, BLAS one thread; "
          f"chain of {n} masses")
    print("")
    print("| scene | masses | modes | parameters | set-up s | seconds | ms per mode and parameter "
          "| largest last correction | route |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for name, rec in out.items():
        print(f"| {name} | {rec['masses']} | {rec['modes']} | {rec['parameters']} | {rec['set_up_seconds']:.2f} "
              f"| {rec['seconds']:.3f} | {1e3 * rec['per_mode_and_parameter']:.2f} | {rec['worst_settled']:.1e} "
              f"| {rec['route']} |")


def main(argv=None) -> dict:
    from threadpoolctl import threadpool_limits

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="chain length (default: %(default)s)")
    ap.add_argument("--modes", type=int, default=3, help="lowest and highest modes of the chain (default: 3 + 3)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each call, the best kept (default: %(default)s)")
    ap.add_argument("--json", action="store_true", help="print the records as JSON")
    _report.add_option(ap)
    args = ap.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        with threadpool_limits(limits=1), tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            dense = measure(dense_scene(), None, args.repeat, folder)
            J = args.modes
            wanted = np.concatenate([np.arange(J), np.arange(args.n - J, args.n)])
            chain = measure(chain_scene(args.n), wanted, args.repeat, folder)
        out = {"dense_40": dense, "chain": chain}
        if args.json:
            print(json.dumps(out, indent=1))
        else:
            _print(out, args.n)
    return out


if __name__ == "__main__":
    main()
