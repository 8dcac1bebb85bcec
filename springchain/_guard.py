"""Whether worker processes may be started from here: the ``if __name__ == "__main__":`` guard.

Dask's ``LocalCluster`` starts its workers with ``multiprocessing``'s *spawn* method: each worker
process imports the user's script again as ``__mp_main__``. Code at the top level of a script
without the guard then runs once more in every worker (every print, and the sweep itself, which
tries to start a cluster of its own: ``RuntimeError: Nanny failed to start`` minutes later).
:func:`unguarded_call` finds that case before any process is started, from the call stack and
the script's own syntax tree (the user's file, parsed with :mod:`ast`, never executed).
"""

from __future__ import annotations

import ast
import os
import sys

GUARD = 'if __name__ == "__main__":'


def _is_main_test(test: ast.expr) -> bool:
    """``__name__ == "__main__"`` (either way round)."""
    if not (isinstance(test, ast.Compare) and len(test.ops) == 1 and isinstance(test.ops[0], ast.Eq)):
        return False
    sides = [test.left, test.comparators[0]]
    names = [s for s in sides if isinstance(s, ast.Name) and s.id == "__name__"]
    consts = [s for s in sides if isinstance(s, ast.Constant) and s.value == "__main__"]
    return len(names) == 1 and len(consts) == 1


def _guarded(tree: ast.Module, line: int) -> bool:
    """Whether ``line`` of the module lies in the body of an ``if __name__ == "__main__":``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and _is_main_test(node.test) and node.body:
            if node.body[0].lineno <= line <= (node.body[-1].end_lineno or node.body[-1].lineno):
                return True
    return False


def unguarded_call() -> tuple[str, int] | None:
    """``(script, line)`` when this call comes from a script's top-level code outside the guard, else None.

    None also for interactive sessions, notebooks, ``python -c`` and anything that cannot be read:
    only a script that spawned workers would re-run is reported.
    """
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not path or not os.path.isfile(path):
        return None
    frame = sys._getframe(1)
    while frame is not None:
        code = frame.f_code
        if code.co_name == "<module>" and frame.f_globals.get("__name__") in ("__main__", "__mp_main__"):
            try:
                same = os.path.samefile(code.co_filename, path)
            except OSError:
                same = False
            if same:
                break
        frame = frame.f_back
    if frame is None:
        return None
    line = frame.f_lineno
    try:
        with open(path, "rb") as fh:
            tree = ast.parse(fh.read(), filename=path)
    except (OSError, SyntaxError, ValueError):
        return None
    return None if _guarded(tree, line) else (path, line)


__all__ = ["unguarded_call", "GUARD"]
