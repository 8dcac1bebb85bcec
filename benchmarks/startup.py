"""Start-up benchmark: how long a command takes before it does any work, against bare imports.

Run ``python benchmarks/startup.py [--repeats R] [--json]``. Each round runs every
command once, in a fresh process, in an interleaved order, so background load hits all of
them alike; the report gives the minimum and the median over rounds and the ratios that the
targets are stated in:

* ``springchain --help`` ≤ 2 × ``python -c "import numpy"``
* ``springchain modes seed --json`` ≤ 2 × ``python -c "import sympy"``

Commands run from an empty temporary folder with the interpreter running this script.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import importlib.util
from pathlib import Path

# the shared ``--markdown FILE`` option (benchmarks/_report.py), loaded by path: the scripts are not a package
_spec = importlib.util.spec_from_file_location("springchain_benchmarks__report", Path(__file__).with_name("_report.py"))
_report = sys.modules.get(_spec.name) or importlib.util.module_from_spec(_spec)
if _spec.name not in sys.modules:
    sys.modules[_spec.name] = _report
    _spec.loader.exec_module(_report)

#: (label, argv after the interpreter) of each timed command.
COMMANDS = {
    "import numpy": ["-c", "import numpy"],
    "import sympy": ["-c", "import sympy"],
    "springchain --help": ["-m", "springchain", "--help"],
    "springchain modes seed --json": ["-m", "springchain", "modes", "seed", "--json"],
}
#: target: (command, baseline, largest ratio allowed)
TARGETS = (("springchain --help", "import numpy", 2.0),
           ("springchain modes seed --json", "import sympy", 2.0))


def _once(argv: list[str], cwd: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], cwd=cwd, check=True, stdout=subprocess.DEVNULL,
                   env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    return time.perf_counter() - t0


def measure(repeats: int = 7) -> dict:
    """Wall seconds per command over ``repeats`` interleaved rounds (one warm-up round first)."""
    times: dict[str, list[float]] = {k: [] for k in COMMANDS}
    with tempfile.TemporaryDirectory() as cwd:
        for label, argv in COMMANDS.items():  # warm-up: file caches, bytecode
            _once(argv, cwd)
        for r in range(repeats):
            order = list(COMMANDS)[r % len(COMMANDS):] + list(COMMANDS)[: r % len(COMMANDS)]
            for label in order:
                times[label].append(_once(COMMANDS[label], cwd))
    rows = {k: {"min": min(v), "median": statistics.median(v)} for k, v in times.items()}
    targets = []
    for cmd, base, limit in TARGETS:
        ratio = rows[cmd]["median"] / rows[base]["median"]
        targets.append({"command": cmd, "baseline": base, "ratio_median": ratio,
                        "ratio_min": rows[cmd]["min"] / rows[base]["min"], "limit": limit,
                        "met": ratio <= limit})
    return {"repeats": repeats, "seconds": rows, "targets": targets}


def markdown(result: dict) -> str:
    lines = ["| command | min s | median s |", "|---|---:|---:|"]
    for label, row in result["seconds"].items():
        lines.append(f"| `{label}` | {row['min']:.3f} | {row['median']:.3f} |")
    lines.append("")
    for t in result["targets"]:
        lines.append(f"- `{t['command']}` / `{t['baseline']}`: {t['ratio_median']:.2f}× (median; "
                     f"{t['ratio_min']:.2f}× of minima), target ≤ {t['limit']:g}× — "
                     + ("met" if t["met"] else "MISSED"))
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python benchmarks/startup.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=7, help="interleaved rounds (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a Markdown table")
    _report.add_option(p)
    args = p.parse_args(argv)
    with _report.recorded(args.markdown, __file__, argv):
        result = measure(max(1, args.repeats))
        print(json.dumps(result, indent=1) if args.json else markdown(result), end="" if not args.json else "\n")
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
