"""A chain module's spring potential compiled into the fused chain kernels, cached on disk.

The generated ``spring_force(d, *parameters)`` of a ``[chain]`` scene with ``potential = "EXPR"``
(:mod:`springchain.derive.potential_code`) is NumPy ufuncs and arithmetic only. :func:`compiled_law`
writes one file per law, ``<cache>/compiled/law_<hash>.py``: the text of :mod:`numeric.compiled.fast_kernels`
(relative imports made absolute), the module's ``spring_force`` (generated code: SymPy-printed
expressions over validated names, never scene text) and the line that binds it as the kernels'
``_law``. The kernels call ``_law(d, *c)`` where a cubic chain has ``c d³``; ``c`` is the tuple of
parameter values, a run-time argument, so one file serves every parameter set of a law. ``<hash>``
is the sha256 of the text (so of the law, the kernels and numba's version): numba caches the machine
code next to the file and a second process compiles nothing. Index-dependent laws
(``POTENTIAL_LAW_INDEXED``) are not compiled: their chains run the module's NumPy stencil.
"""

from __future__ import annotations

import hashlib
import inspect
import re
from dataclasses import dataclass
from types import SimpleNamespace

from ...generated.contract import SCALAR_HELPERS
from ..system import System

#: Scalar forms of the helpers a printed tension may call: inside the kernels the extension is one float.
_SCALAR_HELPERS = SCALAR_HELPERS

_TAIL = """

import numba as _numba

{helpers}_law = _numba.njit(cache=True)(spring_force)
"""


@dataclass(frozen=True)
class CompiledLaw:
    """A spring potential's kernels and the values they are called with.

    Attributes
    ----------
    kernels : SimpleNamespace
        ``force``, ``sweep``, ``half_kick``, ``stream`` of the law's file (numba dispatchers, the
        signatures of :mod:`numeric.compiled.fast_kernels`).
    args : tuple of float, length P
        The module's parameter values in ``PARAMETERS`` order, passed in the cubic coefficients' place.
    path : str
        The compiled file.
    """

    kernels: SimpleNamespace
    args: tuple
    path: str


def _absolute_imports(text: str, package: str) -> str:
    """``from .x`` / ``from ..x`` / ``from ...x`` (any depth) of a module of ``package`` written as absolute imports."""
    parts = package.split(".")

    def absolute(m: re.Match) -> str:
        base = ".".join(parts[:len(parts) + 1 - len(m.group(2))])
        return f"{m.group(1)}from {base}.{m.group(3)}"

    return re.sub(r"^(\s*)from (\.+)(\w)", absolute, text, flags=re.M)


def law_source(system: System) -> str:
    """The law file's text for a chain module with an index-free ``spring_force`` (the same for every
    scene with the same law: the text names no scene)."""
    import numba

    from . import fast_kernels

    force = system.source("spring_force")
    calls = sorted(name for name in _SCALAR_HELPERS if re.search(rf"\b{name}\(", force))
    helpers = "".join(f"{name} = _numba.njit(cache=True)({_SCALAR_HELPERS[name]})\n" for name in calls)
    table = (f"_EXPM1MX_COEFFICIENTS = {tuple(system.value('_EXPM1MX_COEFFICIENTS'))!r}\n\n\n"
             if "_expm1mx" in calls else "")
    scalar = "".join(system.source(_SCALAR_HELPERS[n]) + "\n\n" for n in calls)
    return (f"# fused chain kernels of one spring potential (numba {numba.__version__}); "
            f"written by springchain.numeric.compiled.potential_law, do not edit\n"
            + _absolute_imports(inspect.getsource(fast_kernels), fast_kernels.__package__)
            + "\n\nimport numpy as _np\n\n\n" + table + scalar + force + _TAIL.format(helpers=helpers))


def compiled_law(system: System) -> CompiledLaw | None:
    """The kernels of the system's law and its parameter values to call them with; None without numba.
    For index-free laws only (the caller asks :attr:`System.law_indexed`). The file is written and
    imported once per law in a process (its text read and hashed once per module,
    :meth:`System.per_module`); numba compiles a kernel on its first call or loads it from disk."""
    from .fast_kernels import available

    if not available():
        return None
    kernels, path = system.per_module("compiled.potential_law", lambda: _load_law(law_source(system)))
    return CompiledLaw(kernels, tuple(float(v) for v in system.parameter_vector()), path)


def _load_law(text: str) -> tuple:
    key = hashlib.sha256(text.encode()).hexdigest()[:20]
    if key not in _LAWS:
        from .cache import load_text

        law_file, path = load_text(text, f"law_{key}")
        _LAWS[key] = (law_file.compiled_kernels(), str(path))
    return _LAWS[key]


#: The kernels of this process by the hash of their file's text: (namespace, path).
_LAWS: dict = {}
