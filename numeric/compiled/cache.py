"""Compile a generated module's ``scalar_force`` with the loops of :mod:`.loops`, once per module.

The compiled file is ``<cache>/compiled/sc_<hash>.py``: the loops' template text, the module's
``scalar_force`` source (written by ``derive/codegen``: SymPy-printed expressions over validated
names, never scene text) and the lines that compile both with ``numba.njit(cache=True)``.
``<hash>`` is the sha256 of that text (so of the module's force code, the loops and numba's
version); numba keeps the machine code next to it, so a second process with the same module
compiles nothing. The file is written through a temporary file and a rename.

The cache directory is ``$SPRINGCHAIN_CACHE`` or the user's cache (the place
``springchain._modules.cache_dir`` keeps generated modules of user scenes).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from ...generated.contract import SCALAR_HELPERS
from . import implicit_loops as _implicit
from . import loops as _template

#: The templates the compiled file holds, in order (each defines LOOPS and HELPERS).
_TEMPLATES = (_template, _implicit)
#: Scalar helpers a potential's ``scalar_force`` may call (derive.law_helpers), compiled with it.
_LAW_HELPERS = tuple(SCALAR_HELPERS.values())

#: What the compiled file appends to the template and the module's function.
_TAIL = """

import numba as _numba

_scalar_force_terms = _numba.njit(cache=True)(_scalar_force_terms)
_force = _numba.njit(cache=True)(scalar_force)
{binds}
"""


def available() -> bool:
    """Whether numba loads (else every run takes the NumPy path)."""
    from ..fast_kernels import available as numba_available

    return numba_available()


def cache_root() -> Path:
    """``$SPRINGCHAIN_CACHE/compiled`` (or ``$XDG_CACHE_HOME``/``~/.cache`` ``/springchain/compiled``)."""
    base = os.environ.get("SPRINGCHAIN_CACHE")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = str((Path(xdg) if xdg else Path.home() / ".cache") / "springchain")
    return Path(base) / "compiled"


def source_of(module: ModuleType) -> str:
    """The compiled file's text for ``module`` (which must define ``scalar_force``)."""
    import numba

    body = inspect.getsource(module.scalar_force) + "\n\n" + inspect.getsource(module._scalar_force_terms)
    laws = [name for name in _LAW_HELPERS if hasattr(module, name)]  # a potential's scalar helpers
    if laws:
        body += (f"\n\n_EXPM1MX_COEFFICIENTS = {tuple(getattr(module, '_EXPM1MX_COEFFICIENTS', ()))!r}\n\n"
                 + "\n\n".join(inspect.getsource(getattr(module, name)) for name in laws))
    binds = "\n".join(f"{name} = _numba.njit(cache=True)({name})"
                      for name in [n for t in _TEMPLATES for n in t.HELPERS + t.LOOPS] + laws)
    return (f"# compiled loops of scene {module.SCENE!r} (numba {numba.__version__}); written by "
            f"springchain.numeric.compiled.cache, do not edit\n"
            + "\n\n".join(inspect.getsource(t) for t in _TEMPLATES)
            + "\n\nimport numpy as _np\n\n\n" + body + _TAIL.format(binds=binds))


@dataclass
class Compiled:
    """The compiled loops of one module and what it cost to get them.

    Attributes
    ----------
    module : ModuleType
        The compiled file (its ``*_loop`` functions are numba dispatchers).
    path : Path
    compile_seconds : float
        Wall time spent compiling (or loading from the disk cache) in this process, summed over loops.
    compiled : set of str
        Loops compiled (not loaded from disk) in this process.
    """

    module: ModuleType
    path: Path
    compile_seconds: float = 0.0
    compiled: set = field(default_factory=set)

    def loop(self, name: str):
        """The dispatcher ``name`` (one of :data:`.loops.LOOPS`)."""
        return getattr(self.module, name)

    def note(self, name: str, seconds: float) -> None:
        """Record the first call of loop ``name`` (``seconds`` of wall time; misses mean it compiled)."""
        disp = self.loop(name)
        self.compile_seconds += seconds
        if any(disp.stats.cache_misses.values()):
            self.compiled.add(name)


_LOADED: dict[str, Compiled] = {}
#: id(generated module) -> (module, its Compiled): the text is hashed once per module object.
_BY_MODULE: dict[int, tuple[ModuleType, Compiled]] = {}


def compiled(module: ModuleType) -> Compiled:
    """The compiled loops of ``module`` (written and imported once per process; numba compiles on a
    loop's first call, or loads it from the disk cache)."""
    known = _BY_MODULE.get(id(module))
    if known is not None and known[0] is module:
        return known[1]
    text = source_of(module)
    key = hashlib.sha256(text.encode()).hexdigest()[:20]
    if key in _LOADED:
        _BY_MODULE[id(module)] = (module, _LOADED[key])
        return _LOADED[key]
    mod, path = load_text(text, f"sc_{key}")
    _LOADED[key] = Compiled(mod, path)
    _BY_MODULE[id(module)] = (module, _LOADED[key])
    return _LOADED[key]


def load_text(text: str, stem: str) -> tuple[ModuleType, Path]:
    """Write ``text`` to ``<cache>/compiled/<stem>.py`` (once: through a temporary file and a rename) and
    import it under a private module name, so numba's disk cache sits next to it.

    ``stem`` must name the text's content (a hash of it): a file is never rewritten.
    """
    root = cache_root()
    root.mkdir(parents=True, exist_ok=True)
    path = root / f"{stem}.py"
    if not path.exists():
        fd, tmp = tempfile.mkstemp(dir=root, suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    name = f"_springchain_compiled_{stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod, path


def timed_first_call(c: Compiled, name: str, *args):
    """Call loop ``name``; the first call's compile (or disk load) is timed and noted separately
    by compiling for the argument types before the run."""
    disp = c.loop(name)
    if not disp.signatures:
        t0 = time.perf_counter()
        disp.compile(tuple(disp.typeof_pyval(a) for a in args))
        c.note(name, time.perf_counter() - t0)
    return disp(*args)


__all__ = ["Compiled", "compiled", "available", "cache_root", "load_text", "source_of", "timed_first_call"]
