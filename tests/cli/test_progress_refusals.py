"""A refusal's output is one line; progress is quiet on short phases of a log; it can be silenced.

Under load, a derivation of a small scene can take a few seconds; a refusal must still print only
``springchain: error: ...`` (the tests of the hostile corpus assert one line), and logs (stderr not
a terminal) get their first plain progress line after 5 s, not after 1 s.
"""

from __future__ import annotations

import io

import pytest

from helpers import one_line_error, run_cli
from springchain import _api
from springchain.numeric import progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_its_first_line_after_the_plain_interval():
    log, tty = io.StringIO(), Terminal()
    for stream in (log, tty):
        rep = progress.Reporter("derive", stream=stream)
        rep.t0 -= 2.0  # two seconds into the phase
        rep.update()
    assert log.getvalue() == "" and "derive ... 2 s" in tty.getvalue()
    rep = progress.Reporter("derive", stream=log)
    rep.t0 -= progress.PLAIN_INTERVAL + 1
    rep.update()
    assert log.getvalue().startswith("springchain: derive ... ")


def test_a_phase_that_raises_adds_no_done_line():
    log = io.StringIO()
    with pytest.raises(ValueError):
        with progress.phase("loading", stream=log) as rep:
            rep.quiet, rep.interval = 0.0, 0.0
            rep.update()  # something was shown ...
            raise ValueError("refused")  # ... but no "done in" follows a refusal
    assert log.getvalue().count("\n") == 1 and "done in" not in log.getvalue()


def test_the_environment_silences_every_reporter(monkeypatch):
    monkeypatch.setenv(progress.ENV, "0")
    log = io.StringIO()
    rep = progress.Reporter("x", total=3, enabled=True, stream=log, quiet_seconds=0.0, interval=0.0)
    rep.update(1)
    rep.say("milestone")
    progress.note("compiling", stream=log)
    assert log.getvalue() == "" and not rep.enabled
    monkeypatch.setenv(progress.ENV, "1")
    assert progress.Reporter("x").enabled


@pytest.mark.parametrize("options, expect", [(["--method", "bogus"], "bogus"),
                                             (["--spectrum", "guess"], "guess")])
def test_option_refusals_come_before_any_work(options, expect, tmp_path, monkeypatch, capsys, seed_path):
    """Even with progress shown at once, a refused option prints one line: it is refused before the
    generated module is loaded (or derived), by the command line and by the API alike."""
    monkeypatch.setattr(progress, "QUIET_SECONDS", 0.0)
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    monkeypatch.setenv("SPRINGCHAIN_CACHE", str(tmp_path / "cache"))

    def load_module(sc):
        raise AssertionError("the module was loaded before the option was refused")

    monkeypatch.setattr(_api, "system_of", load_module)
    status, out, err = run_cli(["simulate", seed_path, "--out", tmp_path / "out", *options], capsys)
    one_line_error(status, out, err, expect)
    kwargs = {"methods": ["bogus"]} if "bogus" in expect else {"spectrum": "guess"}
    with pytest.raises(ValueError, match=expect):
        _api.simulate(seed_path, **kwargs)
