"""Compile the small-scene loops once, and a generated module's ``scalar_force`` once per module.

Two kinds of file in ``<cache>/compiled/``, each named by the sha256 of its text and written through a
temporary file and a rename (a file is never rewritten); numba keeps the machine code next to it
(``cache=True``), so a second process compiles nothing:

* ``loops_<hash>.py``: the templates :mod:`.loops` and :mod:`.implicit_loops`, every function
  ``numba.njit``-compiled. One file for all scenes: a loop takes the scene's force as its first
  argument, a first-class function of the type :data:`FORCE_SIGNATURE`, so it is compiled once per
  numba version and loop, not once per scene (seconds each);
* ``sc_<hash>.py``: a module's ``scalar_force`` source (written by ``derive/codegen``: SymPy-printed
  expressions over validated names, never scene text), the scalar law helpers it calls, and the
  line that compiles it as a ``numba.cfunc`` of that type (a fraction of a second).

The cache directory is ``$SPRINGCHAIN_CACHE`` or the user's cache (the place
``springchain._modules.cache_dir`` keeps generated modules of user scenes).
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from ...generated.contract import SCALAR_HELPERS
from ..io.files import atomic_write_text
from ..io.imports import import_file
from ..system import System
from . import implicit_loops as _implicit
from . import loops as _template

#: The templates the loops file holds, in order (each defines LOOPS and HELPERS).
_TEMPLATES = (_template, _implicit)
#: Scalar helpers a potential's ``scalar_force`` may call (derive.law_helpers), compiled with it.
_LAW_HELPERS = tuple(SCALAR_HELPERS.values())
#: The force's type, as numba source: ``force(x, t, out, p)`` on float64 C arrays, returning nothing.
FORCE_SIGNATURE = "void(float64[::1], float64, float64[::1], float64[::1])"

#: What the loops file appends to the templates.
_LOOPS_TAIL = """

import numba as _numba

{binds}
"""
#: What a scene's file appends to its force code: helpers first (the cfunc compiles when it is made).
#: NumPy's error model: a division by zero gives inf or nan, as on the NumPy path (a cfunc cannot raise).
_FORCE_TAIL = """

import numba as _numba

_scalar_force_terms = _numba.njit(cache=True, error_model="numpy")(_scalar_force_terms)
{binds}
force = _numba.cfunc({signature!r}, cache=True, error_model="numpy")(scalar_force)
"""


def available() -> bool:
    """Whether numba loads (else every run takes the NumPy path)."""
    from .fast_kernels import available as numba_available

    return numba_available()


def cache_root() -> Path:
    """``$SPRINGCHAIN_CACHE/compiled`` (or ``$XDG_CACHE_HOME``/``~/.cache`` ``/springchain/compiled``)."""
    base = os.environ.get("SPRINGCHAIN_CACHE")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = str((Path(xdg) if xdg else Path.home() / ".cache") / "springchain")
    return Path(base) / "compiled"


def loops_source() -> str:
    """The loops file's text: the templates and the lines that compile their functions."""
    import numba

    binds = "\n".join(f"{name} = _numba.njit(cache=True)({name})"
                      for name in [n for t in _TEMPLATES for n in t.HELPERS + t.LOOPS])
    return (f"# compiled loops of small [masses] scenes (numba {numba.__version__}); written by "
            f"springchain.numeric.compiled.cache, do not edit\n"
            + "\n\n".join(inspect.getsource(t) for t in _TEMPLATES) + _LOOPS_TAIL.format(binds=binds))


def source_of(system: System) -> str:
    """The text of the compiled force of ``system``'s module (which must define ``scalar_force``)."""
    import numba

    body = system.source("scalar_force") + "\n\n" + system.source("_scalar_force_terms")
    laws = [name for name in _LAW_HELPERS if system.binds(name)]  # a potential's scalar helpers
    if laws:
        coefficients = tuple(system.value("_EXPM1MX_COEFFICIENTS")) if system.binds("_EXPM1MX_COEFFICIENTS") else ()
        body += (f"\n\n_EXPM1MX_COEFFICIENTS = {coefficients!r}\n\n"
                 + "\n\n".join(system.source(name) for name in laws))
    binds = "\n".join(f"{name} = _numba.njit(cache=True, error_model=\"numpy\")({name})" for name in laws)
    return (f"# compiled force of scene {system.scene_name!r} (numba {numba.__version__}); written by "
            f"springchain.numeric.compiled.cache, do not edit\n"
            + "import numpy as _np\n\n\n" + body
            + _FORCE_TAIL.format(binds=binds, signature=FORCE_SIGNATURE))


@functools.lru_cache(maxsize=1)
def _loops_stem() -> str:
    return f"loops_{hashlib.sha256(loops_source().encode()).hexdigest()[:20]}"


@functools.lru_cache(maxsize=1)
def loops_module() -> ModuleType:
    """The loops file, imported once per process (numba compiles a loop on its first call, or loads it)."""
    return load_text(loops_source(), _loops_stem())[0]


def loop_on_hand(name: str) -> bool:
    """Whether loop ``name`` needs no compiling: loaded in this process, or in numba's disk cache beside
    the loops file (its index file)."""
    if name in _ON_DISK or (loops_module.cache_info().currsize and getattr(loops_module(), name).signatures):
        return True
    try:
        found = any((cache_root() / "__pycache__").glob(f"{_loops_stem()}.{name}-*.nbi"))
    except OSError:
        return False
    if found:  # a cache entry is never removed by springchain: asked once per process and loop
        _ON_DISK.add(name)
    return found


#: Loops found in numba's disk cache by :func:`loop_on_hand` in this process.
_ON_DISK: set[str] = set()


@dataclass
class Compiled:
    """The compiled force of one module, the loops it runs in, and what getting them cost.

    Attributes
    ----------
    kernels : ModuleType
        The imported force file (its ``force`` is the ``numba.cfunc`` the loops call); not the generated module.
    path : Path
    compile_seconds : float
        Wall time spent in this process compiling (or loading from the disk cache) the force, and the
        loops whose first call in this process was for this module.
    compiled : set of str
        Loops compiled (not loaded from disk) in this process, on a call for this module.
    force_compiled : bool
        Whether the force was compiled (not loaded from disk) in this process.
    """

    kernels: ModuleType
    path: Path
    compile_seconds: float = 0.0
    compiled: set = field(default_factory=set)
    force_compiled: bool = False

    @property
    def force(self):
        """The module's ``scalar_force`` as a first-class function (the loops' first argument)."""
        return self.kernels.force

    def loop(self, name: str):
        """The dispatcher ``name`` (one of the templates' ``LOOPS``), shared by every module."""
        return getattr(loops_module(), name)

    def note(self, name: str, seconds: float) -> None:
        """Record the first call of loop ``name`` (``seconds`` of wall time; misses mean it compiled)."""
        disp = self.loop(name)
        self.compile_seconds += seconds
        if any(disp.stats.cache_misses.values()):
            self.compiled.add(name)


_LOADED: dict[str, Compiled] = {}
#: The key of a generated module's Compiled in :meth:`System.per_module` (its text is hashed once per module).
PER_MODULE_KEY = "compiled.cache.force"


def compiled(system: System) -> Compiled:
    """The compiled force of ``system``'s module (written, imported and compiled or loaded once per process)."""
    return system.per_module(PER_MODULE_KEY, lambda: _load_force(source_of(system)))


def force_loaded(system: System) -> bool:
    """Whether the compiled force of ``system``'s module is loaded in this process already."""
    return system.per_module(PER_MODULE_KEY) is not None


def compile_seconds() -> float:
    """Seconds this process spent compiling (or loading) compiled loops, over all modules."""
    return sum(c.compile_seconds for c in _LOADED.values())


def _load_force(text: str) -> Compiled:
    key = hashlib.sha256(text.encode()).hexdigest()[:20]
    if key not in _LOADED:
        t0 = time.perf_counter()
        kernels, path = load_text(text, f"sc_{key}")
        _LOADED[key] = Compiled(kernels, path, time.perf_counter() - t0, force_compiled=not kernels.force.cache_hits)
    return _LOADED[key]


def load_text(text: str, stem: str) -> tuple[ModuleType, Path]:
    """Write ``text`` to ``<cache>/compiled/<stem>.py`` (once: through a temporary file and a rename) and
    import it under a private module name, so numba's disk cache sits next to it.

    ``stem`` must name the text's content (a hash of it): a file is never rewritten.
    """
    path = cache_root() / f"{stem}.py"
    if not path.exists():
        atomic_write_text(path, text)
    return import_file(path, f"_springchain_compiled_{stem}", register=True), path


def timed_first_call(c: Compiled, name: str, *args):
    """Call loop ``name`` with ``c``'s force first, then ``args``; a first call in this process compiles
    (or loads) the loop for the argument types before the run, timed and noted on ``c``."""
    disp = c.loop(name)
    args = (c.force, *args)
    if not disp.signatures:
        t0 = time.perf_counter()
        disp.compile(tuple(disp.typeof_pyval(a) for a in args))
        c.note(name, time.perf_counter() - t0)
    return disp(*args)


__all__ = ["Compiled", "FORCE_SIGNATURE", "PER_MODULE_KEY", "compiled", "compile_seconds", "force_loaded", "available", "cache_root", "load_text", "loops_module",
           "loop_on_hand", "loops_source", "source_of", "timed_first_call"]
