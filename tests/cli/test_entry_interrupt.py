"""Ctrl-C that surfaces as another exception (an extension module's initialisation interrupted:
matplotlib raises "ImportError: initialization failed" from the KeyboardInterrupt) still ends
with one line and 130; other exceptions pass through."""

from __future__ import annotations

import signal

import pytest

from springchain import _entry, cli


@pytest.fixture(autouse=True)
def _restore_sigint():
    old = signal.getsignal(signal.SIGINT)
    _entry._state.update(handled=False, signalled=False)
    yield
    signal.signal(signal.SIGINT, old)
    _entry._state.update(handled=False, signalled=False)


def test_import_error_caused_by_ctrl_c_is_an_interrupt(monkeypatch, capsys):
    def interrupted_import(argv=None):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    monkeypatch.setattr(cli, "main", interrupted_import)
    assert _entry.main([]) == _entry.EXIT_INTERRUPTED
    assert capsys.readouterr().err.strip().splitlines() == ["springchain: interrupted"]


def test_other_errors_pass_through(monkeypatch):
    def broken(argv=None):
        raise ImportError("a real import problem")

    monkeypatch.setattr(cli, "main", broken)
    with pytest.raises(ImportError, match="real import problem"):
        _entry.main([])
