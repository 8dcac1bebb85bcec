"""Importing a Python file by its path: the one place that does it (generated modules in the per-user
cache, a sweep worker's module from its source text, the compiled kernels' files)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType


def import_file(path: str | Path, name: str, *, register: bool = False) -> ModuleType:
    """Import the Python file ``path`` as a module called ``name`` and return it.

    Parameters
    ----------
    path : str or Path
        The file (its text is trusted: generated or written by springchain, never a scene's text).
    name : str
        The module's name (unique per file content: callers key it by a hash).
    register : bool, optional
        Also put the module into ``sys.modules`` before running it (numba's disk cache finds a
        compiled function's module by name); default False, the module stays private.
    """
    spec = importlib.util.spec_from_file_location(name, Path(path))
    module = importlib.util.module_from_spec(spec)
    if register:
        sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


__all__ = ["import_file"]
