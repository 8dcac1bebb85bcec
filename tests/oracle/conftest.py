"""The oracle tests: worst error per output, printed at the end of a run (``-n 0``; workers keep their own)."""

from __future__ import annotations


def pytest_terminal_summary(terminalreporter):
    try:
        from oracle.checks import STATS
    except ImportError:
        return
    if not STATS:
        return
    terminalreporter.write_sep("-", "oracle: worst error per output (comparisons)")
    for output in sorted(STATS):
        worst, count = STATS[output]
        terminalreporter.write_line(f"  {output:<22} {worst:.3g}  ({count})")
