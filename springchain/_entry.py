"""The ``springchain`` console entry point: Ctrl-C at any moment ends with one line and exit 130.

This module imports nothing heavy; the handler is in place before the command line module
(argparse, the API, NumPy, SymPy, numba) is imported, and stays until the process exits.
"""

import os
import signal
import sys

EXIT_INTERRUPTED = 130


def _interrupted() -> int:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C during clean-up prints nothing
    try:
        sys.stderr.write("springchain: interrupted\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    return EXIT_INTERRUPTED


def main(argv=None) -> int:
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:  # a background job keeps ignoring it
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        from .cli import main as cli_main

        status = cli_main(argv)
    except KeyboardInterrupt:
        return _interrupted()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # interpreter shutdown: no traceback either
    return status


def run() -> None:
    """``python -m springchain`` and the console script."""
    try:
        status = main()
    except KeyboardInterrupt:  # between the handler and the try
        status = _interrupted()
    if status == EXIT_INTERRUPTED:
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
