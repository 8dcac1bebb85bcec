"""Issue 31: every accepted scene gets true numbers or a one-line refusal — springchain against the oracle.

Four kinds of test:

* ``test_finding[...]`` — each failure the oracle found, as a minimal scene (:mod:`oracle.findings`): issue 31's
  listed findings and the new ones. Still-failing cases are strict ``xfail`` (reason ``issue 31: ...`` or
  ``oracle (new): ...``): a fix turns them into XPASS, which fails until the mark is removed.
* ``test_generated_scene[seed]`` — scenes over the whole accepted domain (:mod:`oracle.scenes`, the same
  generator as the hypothesis strategy, driven by ``random.Random(seed)`` so CI checks the same scenes every
  run): load, modes, frf, simulate(springs=True) and rsa through the public API, every number compared with
  the oracle (:mod:`oracle.checks`). A finding already listed (issue 31's, or a case of ``findings``) is
  counted; anything else fails with the scene's text. ``SPRINGCHAIN_ORACLE_SCENES`` scenes per CI run (24);
  the ``slow`` variant checks ``24 × SPRINGCHAIN_SLOW_BUDGET`` larger ones.
* ``test_hypothesis_search`` — hypothesis searching the same domain, on demand (``ORACLE_SEARCH=N``).
* ``test_generated_record[seed]`` — response spectra of piecewise-linear records against the exact oscillator;
  and the command line (one JSON object, or one line and exit status 2).
"""

from __future__ import annotations

import os
import random
import tempfile
from pathlib import Path

import pytest
from helpers import SLOW_BUDGET
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from oracle import checks as C
from oracle import scenes as S
from oracle.findings import CASES, Case, scene

#: Generated scenes per CI run (seeded: the same scenes every run), and in the slow run.
CI_SCENES = int(os.environ.get("SPRINGCHAIN_ORACLE_SCENES", "24"))
SLOW_SCENES = max(1, int(24 * SLOW_BUDGET))
CI_RECORDS = 12

_SETTINGS = dict(deadline=None, database=None, derandomize=True, phases=(Phase.explicit, Phase.generate),  # no
                 # shrinking: each draw costs seconds of derivation; the failure message carries the scene
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                        HealthCheck.data_too_large, HealthCheck.filter_too_much])


def _param(case: Case):
    marks = []
    if case.failing:
        reason = f"issue 31: {case.known}" if case.known else f"oracle (new): {case.new}"
        marks.append(pytest.mark.xfail(strict=True, reason=reason))
    return pytest.param(case, id=case.id, marks=marks)


def run_case(case: Case, folder: Path) -> C.Report:
    if case.outputs == ("spectrum",):
        return C.check_record(case.record, case.features)
    if case.outputs == ("spectrum_time",):
        return C.check_spectrum_time(case.record, 15.0, case.features)
    if case.outputs == ("cli",):
        rep = C.Report()
        path = S.GeneratedScene(case.text, case.tables, (), case.features, case.id).write(folder)
        C.check_cli(rep, path, case.features, argv=case.cli, timeout=case.timeout)
        return rep
    gen = S.GeneratedScene(case.text, case.tables, (), case.features, case.id)
    return C.check_scene(gen, folder, frf_pair=case.frf_pair, record=case.record, outputs=set(case.outputs))


@pytest.mark.timeout(600, method="thread")
@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_finding(case, tmp_path):
    """No finding on the case's minimal scene: true numbers within tolerance, or a one-line refusal."""
    rep = run_case(case, tmp_path)
    assert not rep.findings, "\n".join(str(f) for f in rep.findings)


def _check(gen, rng: random.Random) -> C.Report:
    """Every output of ``gen``; the frf pair and the rsa record drawn from ``rng``."""
    n = len(gen.masses)
    pair = (rng.randrange(n), rng.randrange(n))
    record = S.build_record(S.SeededChooser(rng.randrange(2**32)), max_rows=6)
    trace = os.environ.get("ORACLE_TRACE")  # a folder: each scene is kept there with its findings
    with tempfile.TemporaryDirectory(prefix="oracle-", dir=trace) as folder:
        rep = C.check_scene(gen, Path(folder), frf_pair=pair, record=record)
        if trace:
            Path(folder, "findings.txt").write_text(f"frf pair {pair}\n" + "\n".join(map(str, rep.findings)) + "\n")
            Path(folder).rename(Path(trace) / f"scene-{len(os.listdir(trace)):03d}")
            Path(folder).mkdir()
        return rep


def _verdict(gen, rep: C.Report) -> None:
    assert not rep.new, ("unlisted findings (add a minimal case to oracle/findings.py):\n"
                         + "\n".join(str(f) for f in rep.new) + "\n--- scene ---\n" + gen.text
                         + "".join(f"--- {k} ---\n{v}" for k, v in gen.tables.items()))


@pytest.mark.timeout(600, method="thread")  # the product calls have their own SIGALRM watchdog (checks.product)
@pytest.mark.parametrize("seed", range(CI_SCENES))
def test_generated_scene(seed):
    """A fixed sample over the whole domain (scene ``seed`` of :func:`oracle.scenes.seeded_scene`): every output
    within tolerance of the oracle, or a listed finding, or a one-line refusal; never a traceback, a leaked
    warning or a silent wrong number."""
    gen = S.seeded_scene(seed, max_masses=4, max_chain=6)
    _verdict(gen, _check(gen, random.Random(seed)))


@pytest.mark.slow
@pytest.mark.timeout(900, method="thread")
@pytest.mark.parametrize("seed", range(1000, 1000 + SLOW_SCENES))
def test_generated_scene_slow(seed):
    """The same property on more and larger scenes (24 × SPRINGCHAIN_SLOW_BUDGET of them)."""
    gen = S.seeded_scene(seed, max_masses=6, max_chain=14)
    _verdict(gen, _check(gen, random.Random(seed)))


@pytest.mark.slow
@pytest.mark.timeout(3600, method="thread")
@pytest.mark.skipif(not os.environ.get("ORACLE_SEARCH"), reason="a hypothesis search: ORACLE_SEARCH=N examples")
@settings(max_examples=int(os.environ.get("ORACLE_SEARCH") or 1), **_SETTINGS)
@given(gen=S.scenes(max_masses=6, max_chain=14), seed=st.integers(0, 2**32 - 1))
def test_hypothesis_search(gen, seed):
    """Hypothesis searching the domain (its draws depend on how earlier examples ran, so it is not CI's fixed
    sample): ``ORACLE_SEARCH=200 python -m pytest tests/oracle -k search -n 0``."""
    _verdict(gen, _check(gen, random.Random(seed)))


@pytest.mark.timeout(300)
@pytest.mark.parametrize("seed", range(CI_RECORDS))
def test_generated_record(seed):
    """SD of records (uneven rows, any start, zero or nonzero last row; periods from below the row spacing to
    4× the record; ζ from 0 to 0.7) against the exact oscillator, free vibration included."""
    rec = S.seeded_record(seed)
    rep = C.check_record(rec)
    assert not rep.new, "\n".join(str(f) for f in rep.new) + f"\nrecord: t = {rec.t}, a = {rec.a}"


# -- the command line: one JSON object (exit 0) or one line (exit 2) ---------------------------------------------
CLI_SCENES = {
    "out_of_range_mass": scene("tiny", {"m": 1e-160}, '''
[masses]
p = "m"
[[springs]]
between = ["wall", "p"]
k = "1"
'''),
    "lennard_jones_under_gravity": next(c.text for c in CASES if c.id == "lennard_jones_under_gravity"),
    "cubic_under_gravity": next(c.text for c in CASES if c.id == "N2_cubic_under_gravity"),
}


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name", sorted(CLI_SCENES))
def test_cli_modes_json_or_one_line(name, tmp_path):
    """``springchain modes SCENE --json``: exit 0 with one JSON object, or exit 2 with one line on stderr."""
    path = tmp_path / f"{name}.toml"
    path.write_text(CLI_SCENES[name], encoding="utf-8")
    rep = C.Report()
    C.check_cli(rep, path, frozenset())
    assert not rep.findings, "\n".join(str(f) for f in rep.findings)
