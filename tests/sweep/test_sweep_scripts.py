"""Sweeps from scripts (issue 23, item 5), run as real scripts in fresh Python processes.

A small study (or ``workers=1``) runs in-process on Dask's synchronous scheduler, so a script
without ``if __name__ == "__main__":`` works and runs its top level once. A study big enough to
start worker processes from such a script is refused at once, in one line that names the guard,
before any worker process exists (the script's top level ran exactly once).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from springchain._guard import _guarded, unguarded_call

CHAIN = 'name = "mid"\n[parameters]\nm = 1.0\nk = 1.0\n[chain]\nn = 400\nmass = "m"\nk = "k"\n'


def _script(tmp_path, body: str) -> subprocess.CompletedProcess:
    (tmp_path / "mid.toml").write_text(CHAIN)
    path = tmp_path / "study.py"
    path.write_text(textwrap.dedent(body))
    return subprocess.run([sys.executable, str(path)], cwd=tmp_path, capture_output=True, text=True, timeout=600)


def test_unguarded_script_with_a_small_sweep_finishes_in_process(tmp_path):
    res = _script(tmp_path, """
        import springchain as sc
        print("top level ran")
        r = sc.sweep("seed", vary=["k=uniform(1, 2)"], samples=12, out="small", progress=False)
        print("rows", r.rows, "|", r.run["scheduler"])
        r1 = sc.sweep("mid.toml", disorder=["mass=uniform(0.5, 1.5)"], samples=6, workers=1, out="one",
                      progress=False)
        print("rows", r1.rows, "|", r1.run["scheduler"])
    """)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines.count("top level ran") == 1, res.stdout
    assert "rows 12 | in-process (Dask's synchronous scheduler)" in lines
    assert "rows 6 | in-process (Dask's synchronous scheduler)" in lines


def test_unguarded_script_starting_worker_processes_stops_at_once_naming_the_guard(tmp_path):
    res = _script(tmp_path, """
        import springchain as sc
        print("top level ran")
        sc.sweep("mid.toml", disorder=["mass=uniform(0.5, 1.5)"], samples=4000, workers=2, out="big",
                 progress=False)
        print("not reached")
    """)
    assert res.returncode != 0
    assert res.stdout.splitlines() == ["top level ran"]  # no worker re-ran the script
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("springchain.numeric.errors.RunRefused: sweep: ")
    assert 'if __name__ == "__main__":' in last and "study.py, line 4" in last and "workers=1" in last
    assert "Nanny" not in res.stderr


@pytest.mark.parametrize("source, line, guarded", [
    ('import x\nif __name__ == "__main__":\n    x.sweep()\n', 3, True),
    ("import x\nif '__main__' == __name__:\n    x.sweep()\n", 3, True),
    ('import x\nx.sweep()\nif __name__ == "__main__":\n    pass\n', 2, False),
    ('import x\nif __name__ != "__main__":\n    x.sweep()\n', 3, False),
    ('import x\nif __name__ == "__main__":\n    pass\nelse:\n    x.sweep()\n', 5, False),
])
def test_guard_detection_reads_the_script(source, line, guarded):
    import ast

    assert _guarded(ast.parse(source), line) is guarded


def test_no_script_no_refusal():
    # under pytest the main module is pytest's own entry point, whose call is guarded
    assert unguarded_call() is None
