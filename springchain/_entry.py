"""The ``springchain`` console entry point: Ctrl-C at any moment ends with one line and exit 130.

This module imports nothing heavy; the handler is in place before the command line module
(argparse, the API, NumPy, SymPy, numba) is imported, and stays until the process exits.
"""

import os
import signal
import sys

EXIT_INTERRUPTED = 130


#: If a KeyboardInterrupt is swallowed (CPython ignores exceptions raised in finalizers, and
#: some libraries catch everything), the process still ends this many seconds after Ctrl-C.
GRACE_SECONDS = 10.0
_state = {"handled": False, "signalled": False}


def _hard_exit() -> None:
    if not _state["handled"]:
        _state["handled"] = True
        try:
            sys.stderr.write("springchain: interrupted\n")
            sys.stderr.flush()
        finally:
            os._exit(EXIT_INTERRUPTED)


def _on_sigint(signum, frame):
    import threading

    _state["signalled"] = True
    timer = threading.Timer(GRACE_SECONDS, _hard_exit)
    timer.daemon = True
    timer.start()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C during clean-up prints nothing
    raise KeyboardInterrupt


def _on_unraisable(unraisable) -> None:
    """After Ctrl-C, errors CPython cannot raise are not printed: a KeyboardInterrupt raised in a
    ctypes callback while numba compiles is lost (the work would go on until the grace timer: end
    now, as that timer would, with one line), and finalizers of objects the interrupt left half
    built fail ("Exception ignored in ... __del__" with a traceback)."""
    if _state["signalled"]:
        if issubclass(unraisable.exc_type, KeyboardInterrupt):
            _hard_exit()
        return
    sys.__unraisablehook__(unraisable)


def _interrupted() -> int:
    _state["handled"] = True
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C during clean-up prints nothing
    try:
        sys.stderr.write("springchain: interrupted\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    return EXIT_INTERRUPTED


def _from_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in the exception's chain of causes."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def main(argv=None) -> int:
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:  # a background job keeps ignoring it
        signal.signal(signal.SIGINT, _on_sigint)
        sys.unraisablehook = _on_unraisable
    try:
        from .cli import main as cli_main

        status = cli_main(argv)
    except KeyboardInterrupt:
        return _interrupted()
    except BaseException as exc:  # noqa: BLE001 - re-raised unless Ctrl-C caused it
        # Ctrl-C during an extension module's initialisation surfaces as another exception
        # (matplotlib: "ImportError: initialization failed" from the KeyboardInterrupt)
        if _state["signalled"] or _from_interrupt(exc):
            return _interrupted()
        raise
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # interpreter shutdown: no traceback either
    return status


def run() -> None:
    """``python -m springchain`` and the console script."""
    try:
        status = main()
    except KeyboardInterrupt:  # between the handler and the try
        status = _interrupted()
    if status == EXIT_INTERRUPTED:
        _state["handled"] = True
        # Leave at once: a KeyboardInterrupt that passed through code run by PyRun_String (some
        # extension modules' import) makes CPython re-kill itself with SIGINT at exit (status -2)
        # even though it was handled. Clean-up (temporary files) already ran in finally blocks.
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(status)
    raise SystemExit(status)
