"""The cost of ``springchain bands`` for cells of p = 2, 4, 8 masses on 10⁴ q-points, and its accuracy at
contrasts 1e-12 … 1e12.

Run ``python benchmarks/bench_bands.py [--points Q] [--accuracy] [--json] [--markdown FILE]`` (BLAS pinned to one
thread). For a
``[chain]`` of masses m(1 + i % p) and springs k(1 + (i % p)/p) it times, after a warm-up (the generated module
derived, SymPy imported):

* ``spectrum``: the accurate route alone on Q q-points (elimination on the cell's elements, one-sided Jacobi,
  group velocities), and with the branches aligned to the continuity grid;
* ``bands``: ``springchain.bands(scene, q=Q points, finite=False, density=False)`` whole (the cell found from
  the expressions, edges and gaps, alignment);
* ``bands + dos``: the same with the density of states and Im q on the 600-point frequency grid;
* ``eigvalsh``: NumPy's ``eigvalsh`` of D(q) formed in float64 (not accurate at contrast: the yardstick).

``--accuracy`` prints the worst relative error of ω²_j(q) (sampled q), the band edges and the gap width of the
diatomic chain against its textbook formula at 60 digits, at mass and stiffness contrasts 1e-12 … 1e12.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("SPRINGCHAIN_PROGRESS", "0")

import numpy as np

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)


def chain(p: int):
    import springchain as sc

    return sc.scene_from_dict({"name": f"poly{p}", "parameters": {"m": 1.0, "k": 1.0},
                               "chain": {"n": 4 * p, "mass": f"m*(1 + i % {p})", "k": f"k*(1 + (i % {p})/{p})"}})


def _runs(scene, cell, grid, q):
    """The timed calls of one cell, name -> callable."""
    from springchain.numeric.bands.damped import bloch
    from springchain.numeric.bands.spectrum import align, spectrum

    import springchain as sc

    K = bloch(cell.p, cell.ends, cell.reach, cell.stiffness, q)
    s = 1 / np.sqrt(cell.masses)
    return {"spectrum": lambda: spectrum(cell, q),
            "spectrum + align": lambda: align(grid, spectrum(cell, q), cell),
            "bands": lambda: sc.bands(scene, q=q, finite=False, density=False),
            "bands + dos": lambda: sc.bands(scene, q=q, finite=False, density=True),
            "eigvalsh": lambda: np.linalg.eigvalsh(K * s[:, None] * s[None, :])}


def timings(points: int) -> list[dict]:
    from springchain.numeric.bands.edges import edges
    from springchain.numeric.bench.timing import measure, single_threaded_blas

    import springchain as sc

    q = np.linspace(-np.pi, np.pi, points)
    rows = []
    with single_threaded_blas():
        for p in (2, 4, 8):
            scene = chain(p)
            cell = sc.bands(scene, q=q[:3], finite=False, density=False).elements  # warm-up: module, SymPy
            row = {"p": p, "points": points}
            for name, run in _runs(scene, cell, edges(cell)[2], q).items():
                row[name] = measure(run, budget=2.0, max_repeats=3).seconds
            rows.append(row)
    return rows


def _textbook(m1, m2, k1, k2, q):
    """The diatomic chain's ω²∓(q) (60 digits: the cancellation in the lower one is harmless there)."""
    import mpmath as mp

    with mp.workdps(60):
        a = (k1 + k2) * (1 / mp.mpf(m1) + 1 / mp.mpf(m2)) / 2
        r = mp.sqrt(a * a - 4 * k1 * k2 * mp.sin(mp.mpf(q) / 2) ** 2 / (m1 * mp.mpf(m2)))
        return [a - r, a + r]


def accuracy() -> list[dict]:
    import mpmath as mp

    import springchain as sc

    qs = [1e-9, 1e-5, 0.01, 0.7, 1.9, 2.9, np.pi]
    out = []
    for which in ("mass", "stiffness"):
        for c in (1e-12, 1e-8, 1e-4, 1e4, 1e8, 1e12):
            m1, m2, k1, k2 = (1.0, c, 1.0, 1.7) if which == "mass" else (1.0, 2.5, 1.0, c)
            scene = sc.scene_from_dict({"name": "dia", "parameters": {"m1": m1, "m2": m2, "k1": k1, "k2": k2},
                                        "chain": {"n": 8, "mass": "m1*(1 - i % 2) + m2*(i % 2)",
                                                  "k": "k1*(1 - i % 2) + k2*(i % 2)"}})
            b = sc.bands(scene, q=qs, finite=False, density=False)
            with mp.workdps(60):
                def rel(x, y):
                    return float(abs(mp.mpf(x) - y) / abs(y))

                omega = max(rel(b.omega2[k, j], _textbook(m1, m2, k1, k2, q)[j]) for k, q in enumerate(qs)
                            for j in range(2))
                (lo, hi), top = _textbook(m1, m2, k1, k2, np.pi), _textbook(m1, m2, k1, k2, 0.0)[1]
                e0, e1 = b.edges
                edge = max(rel(e0.high, lo), rel(e1.low, hi), rel(e1.high, top))
                gap = rel(b.gaps[0].width, mp.sqrt(hi) - mp.sqrt(lo))
            zero = bool(sc.bands(scene, q=[0.0], finite=False, density=False).omega2[0, 0] == 0.0)
            out.append({"contrast": f"{which} {c:g}", "omega2": omega, "edges": edge, "gap_width": gap,
                        "zero_at_q0": zero})
    return out


def _print(result: dict) -> None:
    print(f"{result['timings'][0]['points']} q-points on [-pi, pi]; seconds per call (best of up to 3), BLAS one thread")
    print("")
    print("| p | q-points | spectrum s | spectrum + align s | bands s | bands + dos s | eigvalsh (float64) s |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for r in result["timings"]:
        print(f"| {r['p']} | {r['points']} | {r['spectrum']:.3f} | {r['spectrum + align']:.3f} | {r['bands']:.3f} | "
              f"{r['bands + dos']:.3f} | {r['eigvalsh']:.4f} |")
    if "accuracy" in result:
        print("\nDiatomic chain against its textbook formula at 60 digits: worst relative error")
        print("\n| contrast | omega^2 (sampled q) | band edges | gap width | omega^2 = 0 at q = 0 |")
        print("|---|---:|---:|---:|---|")
        for r in result["accuracy"]:
            print(f"| {r['contrast']} | {r['omega2']:.2e} | {r['edges']:.2e} | {r['gap_width']:.2e} | {r['zero_at_q0']} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--points", type=int, default=10_000, help="q-points of the timed calls (default %(default)s)")
    ap.add_argument("--accuracy", action="store_true",
                    help="also print the accuracy table at contrasts 1e-12 ... 1e12 against 60-digit references")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    _report.add_option(ap)
    args = ap.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        result = {"timings": timings(args.points)}
        if args.accuracy:
            result["accuracy"] = accuracy()
        if args.json:
            print(json.dumps(result, indent=1))
        else:
            _print(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
