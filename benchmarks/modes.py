"""The cost of stable mode evaluation: generated ``omega2()`` against the naive float64 closed form.

Run ``python benchmarks/modes.py [--json]``. For the reference scene (``seed``: closed
forms free of cancellation, kept in the generated module) and issue 9's hardest named case
(six equal masses between walls, springs alternating k and 1e8·k: Viète cubic roots that
cancel in float64, so the generated module runs the spring-factor SVD), it times, interleaved,

* **before**: the derivation's closed forms lambdified to NumPy float64 (how ω² were
  evaluated before issue 9), and
* **after**: the generated module's ``omega2()`` (the current route),

and reports each one's worst relative error against the correctly rounded values that
``springchain modes`` prints (mpmath at increasing precision).
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import timeit
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

HARD = """name = "walls_six_alternating"
description = "issue 9: six equal masses between walls, springs alternating k and 1e8 k"

[parameters]
m = 1.0
k = 1.0
K = 1e8

[masses]
x0 = "m"
x1 = "m"
x2 = "m"
x3 = "m"
x4 = "m"
x5 = "m"
""" + "".join(f'\n[[springs]]\nbetween = ["{a}", "{b}"]\nk = "{s}"\n' for a, b, s in (
    ("wall", "x0", "k"), ("x0", "x1", "K"), ("x1", "x2", "k"), ("x2", "x3", "K"), ("x3", "x4", "k"),
    ("x4", "x5", "K"), ("x5", "wall", "k"))) + """
[initial]
x = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]
v = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]

[simulation]
dt = 1e-5
steps = 10
"""


def _case(scene, rounds: int, number: int) -> dict:
    from springchain import _api
    from springchain._modules import load_module
    from springchain.derive.accurate import float64_closed_form

    m = _api.modes(scene)
    mod, _ = load_module(m.scene)
    params = dict(m.scene.parameters)
    exprs = [mode.omega2 for mode in m.modes.modes for _ in mode.shapes]
    naive = float64_closed_form(exprs, m.model.params)
    truth = np.sort(m.omega2_values)

    def err(w2):
        w2 = np.sort(np.asarray(w2, dtype=float))
        scale = np.where(truth == 0, 1.0, np.abs(truth))
        return float(np.max(np.abs(w2 - truth) / scale))

    funcs = {"before": lambda: naive(**params), "after": lambda: mod.omega2(**params)}
    samples = {k: [] for k in funcs}
    for _ in range(rounds):
        for name, f in funcs.items():
            samples[name].append(timeit.timeit(f, number=number) / number)
    return {"scene": m.scene.name, "N": m.scene.n, "closed_form_kept": bool(mod.__doc__ is not None and
                                                                           "_accurate_modes" not in
                                                                           (mod.omega2.__doc__ or "")),
            "seconds": {k: {"median": statistics.median(v), "min": min(v)} for k, v in samples.items()},
            "error": {"before": err(funcs["before"]()), "after": err(funcs["after"]())}}


def measure(rounds: int = 7, number: int = 2000) -> list[dict]:
    out = [_case("seed", rounds, number)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "walls_six_alternating.toml"
        path.write_text(HARD, encoding="utf-8")
        out.append(_case(str(path), rounds, number))
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python benchmarks/modes.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print JSON")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        rows = measure()
        if args.json:
            print(json.dumps(rows, indent=1))
            return 0
        for r in rows:
            s, e = r["seconds"], r["error"]
            route = "closed form kept" if r["closed_form_kept"] else "spring-factor SVD in the module"
            print(f"{r['scene']} (N = {r['N']}, {route}):\n"
                  f"  before: float64 closed form  {s['before']['median'] * 1e6:8.1f} µs   worst rel. error {e['before']:.1e}\n"
                  f"  after:  generated omega2()   {s['after']['median'] * 1e6:8.1f} µs   worst rel. error {e['after']:.1e}")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
