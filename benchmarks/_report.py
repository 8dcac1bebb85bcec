"""``--markdown FILE``: what a benchmark script prints, written into a file the documentation includes.

Every script in ``benchmarks/`` takes ``--markdown FILE`` (by convention
``docs/benchmarks/<script>.md``): what it prints on stdout is also written to FILE, after a header
naming the machine, the date, the springchain version and the exact command, so a number on the
Benchmarks page of the documentation is never copied by hand. Tables (lines starting with ``|``)
stay Markdown; other lines go into ``text`` blocks.
"""

from __future__ import annotations

import contextlib
import datetime
import io
import os
import platform
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def add_option(parser) -> None:
    """The ``--markdown FILE`` option of every benchmark script."""
    parser.add_argument("--markdown", metavar="FILE",
                        help="also write the output, with the machine, date and command, into FILE "
                             "(for the documentation: docs/benchmarks/<script>.md)")


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _versions() -> str:
    out = []
    for name in ("springchain", "numpy", "scipy", "numba", "sympy", "dask"):
        try:
            from importlib.metadata import version

            out.append(f"{name} {version(name)}")
        except Exception:  # noqa: BLE001 - a package that is not installed is left out
            continue
    return ", ".join(out)


def _commit() -> str:
    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def header(script: str, argv: list[str], load_before: float, started: datetime.datetime) -> str:
    """The provenance lines: command, date (the run's start), machine, load, versions."""
    now = started.strftime("%Y-%m-%d %H:%M UTC")
    memory = ""
    with contextlib.suppress(OSError, ValueError):
        kb = int(next(ln for ln in Path("/proc/meminfo").read_text().splitlines()
                      if ln.startswith("MemTotal")).split()[1])
        memory = f", {kb / 2**20:.0f} GiB"
    command = "python benchmarks/" + Path(script).name + "".join(" " + shlex.quote(a) for a in argv)
    return "\n".join([
        f"<!-- written by benchmarks/{Path(script).name} --markdown: do not edit; run the command to regenerate -->",
        f"- **command:** `{command}`",
        f"- **date:** {now}; git commit {_commit()}",
        f"- **machine:** {_cpu_model()}, {os.cpu_count()} cores{memory}; {platform.system()} {platform.release()}; "
        f"Python {platform.python_version()}",
        f"- **load average** before the run: {load_before:.2f}",
        f"- **versions:** {_versions()}",
        "",
    ])


def body(text: str) -> str:
    """Printed output as Markdown: table rows kept, every other run of lines in a ``text`` block."""
    out, block, table = [], [], []

    def flush():
        while block and not block[-1].strip():
            block.pop()
        if block:
            out.extend(["```text", *block, "```", ""])
            block.clear()
        if table:
            out.extend([*table, ""])
            table.clear()

    for line in text.rstrip("\n").splitlines():
        if line.lstrip().startswith("|"):
            if block:
                flush()
            table.append(line.strip())
        elif line.strip() == "" and not block:
            flush()
        else:
            if table:
                flush()
            block.append(line)
    flush()
    return "\n".join(out)


class _Tee(io.TextIOBase):
    def __init__(self, stream):
        self.stream, self.buffer_ = stream, io.StringIO()

    def write(self, s):
        self.buffer_.write(s)
        return self.stream.write(s)

    def flush(self):
        self.stream.flush()


@contextlib.contextmanager
def recorded(path: str | None, script: str, argv: list[str] | None = None):
    """Print as usual; with a ``path``, also write the header and the printed output there."""
    if not path:
        yield
        return
    argv = sys.argv[1:] if argv is None else list(argv)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    started = datetime.datetime.now(datetime.timezone.utc)
    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):
        yield
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(header(script, argv, load, started) + "\n" + body(tee.buffer_.getvalue()), encoding="utf-8")
    print(f"wrote {path}", file=sys.stderr)
