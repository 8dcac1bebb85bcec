"""The one table from method names to methods, and the only place where names are strings.

Listing names imports nothing: each entry names its implementation as ``"module:Class"``
(relative to ``springchain.numeric``), imported on first use. Inside, code works with the
:class:`~.protocol.Method` objects :func:`method` and :func:`methods` return.

Adding an integrator is its module and one entry here (or :func:`register` at run time, as an
extension or a test does); ``simulate``, ``plan``, ``bench`` and the command line's ``--method``
take it from this table.
"""

from __future__ import annotations

import importlib
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Collection, Iterator

from ..errors import RunRefused
from .protocol import Kind, Method, Options


def _imported(target: str | type) -> type:
    """The class a target names (``"module:Class"`` relative to ``springchain.numeric``, imported now)."""
    if not isinstance(target, str):
        return target
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module, "springchain.numeric"), attr)


@dataclass(frozen=True)
class Entry:
    """One registered method.

    Attributes
    ----------
    name : str
        The name at the edge (``--method``, NPZ keys ``x_<name>``, bench records).
    kind : Kind
    target : str or type
        ``"module:Class"`` relative to ``springchain.numeric`` (imported lazily), or the class itself:
        an :class:`~numeric.integrators.base.Integrator` (``Kind.STEP``), an
        :class:`~numeric.integrators.ivp.AdaptiveMethod` (``Kind.ADAPTIVE``) or, for ``Kind.EXACT``,
        the :class:`~.protocol.Method` subclass.
    """

    name: str
    kind: Kind
    target: str | type
    #: For ``Kind.STEP``: the :class:`~.step.StepMethod` subclass that runs the integrator
    #: (``"module:Class"`` or the class; None: :class:`~.step.StepMethod` itself).
    runner: str | type | None = None

    def load(self) -> type:
        """The implementation class (imported on first use)."""
        cls = _imported(self.target)
        declared = getattr(cls, "name", self.name)
        if self.kind is not Kind.EXACT and declared != self.name:
            raise ValueError(f"registry entry {self.name!r} loads {cls.__name__}, which calls itself {declared!r}")
        return cls

    def load_runner(self) -> type:
        """The step method class that runs a ``Kind.STEP`` entry's integrator."""
        if self.runner is None:
            from .step import StepMethod

            return StepMethod
        return _imported(self.runner)


def _integrators(kind: Kind, targets: dict[str, str], runner: str | None = None) -> tuple[Entry, ...]:
    """The entries of one kind of integrator: name -> ``"module:Class"`` in ``numeric.integrators``
    (and, for step methods run by a :class:`~.step.StepMethod` subclass, that ``runner``)."""
    return tuple(Entry(name, kind, ".integrators." + target, runner) for name, target in targets.items())


#: Every method, in the order the command line lists them: the exact one, the fixed-step
#: integrators (the implicit ones run by their own step method), then the adaptive methods
#: (SciPy's, then the Runge–Kutta–Nyström pairs).
_TABLE: dict[str, Entry] = {e.name: e for e in (
    Entry("modal", Kind.EXACT, ".run.exact:ExactSolution"),
    *_integrators(Kind.STEP, {
        "verlet": "verlet:VelocityVerlet",
        "verlet-kahan": "verlet_compensated:CompensatedVerlet",
        "yoshida4": "yoshida:Yoshida4",
        "blanes-moan4": "blanes_moan4:BlanesMoan4",
        "blanes-moan6": "blanes_moan6:BlanesMoan6",
        "kahan-li8": "kahan_li:KahanLi8",
        "rk4": "rk4:RK4",
        "expm": "expm:MatrixExponential",
        "chebyshev": "chebyshev:ChebyshevPropagator",
    }),
    *_integrators(Kind.STEP, {
        "newmark": "newmark:NewmarkAverage",
        "newmark-linear": "newmark:NewmarkLinear",
        "hht": "newmark:HHTAlpha",
    }, runner=".run.implicit:ImplicitStep"),
    *_integrators(Kind.ADAPTIVE, {"rk45": "ivp:RK45", "dop853": "ivp:DOP853"}),
    Entry("dop853-compiled", Kind.ADAPTIVE, ".compiled.peer:CompiledDOP853"),
    *_integrators(Kind.ADAPTIVE, {
        "lsoda": "ivp:LSODA",
        "dprkn6": "dprkn6:DPRKN6",
        "dprkn8": "dprkn8:DPRKN8",
        "dprkn12": "dprkn12:DPRKN12",
    }),
)}

#: The built-in entries (the table before any :func:`register`).
_BUILT_IN: dict[str, Entry] = dict(_TABLE)

#: The exact method's name (the default runs pair it with a step method).
EXACT = "modal"
#: The default step method, and the reference adaptive method of plans, benches and references.
DEFAULT_STEP = "verlet"
REFERENCE_ADAPTIVE = "dop853"
#: SciPy's DOP853 compiled (numeric.compiled.peer): bench's second peer, compiled against compiled.
COMPILED_PEER = "dop853-compiled"
#: The step method of the benchmark's grid reference (eighth order, symplectic).
REFERENCE_STEP = "kahan-li8"


def integrator_classes() -> dict[str, str]:
    """Class name -> module in ``numeric.integrators`` of every integrator of the built-in table (imports
    nothing): the package :mod:`numeric.integrators` exports these names from it."""
    out = {}
    for e in _BUILT_IN.values():
        if isinstance(e.target, str) and e.target.startswith(".integrators."):
            module, _, cls = e.target[len(".integrators."):].partition(":")
            out.setdefault(cls, module)
    return out


def names(kind: Kind | None = None) -> tuple[str, ...]:
    """Registered names (of one kind), in table order. Imports nothing."""
    return tuple(name for name, e in _TABLE.items() if kind is None or e.kind is kind)


def entry(name: str) -> Entry:
    """The entry called ``name``; :class:`RunRefused` naming the accepted names otherwise."""
    try:
        return _TABLE[name]
    except (KeyError, TypeError):
        raise RunRefused(f"method {name!r} is unknown; accepted: {', '.join(_TABLE)}", quantity="method") from None


def implementation(name: str) -> type:
    """The class behind ``name`` (integrator, adaptive solver, or exact :class:`Method`)."""
    return entry(name).load()


def classes(kind: Kind) -> dict[str, type]:
    """Name -> implementation class of every method of ``kind`` (imports them)."""
    return {name: implementation(name) for name in names(kind)}


def method(name: str, options: Options = Options()) -> Method:
    """The method called ``name``, with ``options``."""
    e = entry(name)
    cls = e.load()
    if e.kind is Kind.EXACT:
        return cls(name, options)
    if e.kind is Kind.STEP:
        return e.load_runner()(name, options, cls)
    from .adaptive import AdaptiveRun

    return AdaptiveRun(name, options, cls)


def methods(kind: Kind | None = None, options: Options = Options(),
            only: Collection[str] | None = None) -> tuple[Method, ...]:
    """Every registered method (of one kind; among the names ``only`` when given), in table order."""
    return tuple(method(name, options) for name in names(kind) if not only or name in only)


#: Benchmark peers: ``bench`` times them beside the others, ``plan`` never proposes them.
PEERS_ONLY = frozenset({COMPILED_PEER})


def planned(kind: Kind | None = None, options: Options = Options(),
            only: Collection[str] | None = None) -> tuple[Method, ...]:
    """:func:`methods` that ``plan`` may propose (the benchmark peers left out)."""
    return tuple(m for m in methods(kind, options, only) if m.name not in PEERS_ONLY)


def register(name: str, kind: Kind, target: str | type, runner: str | type | None = None) -> None:
    """Add a method (an extension's integrator, and for a step method the class that runs it); its
    name must be new."""
    if name in _TABLE:
        raise ValueError(f"method {name!r} is registered already")
    _TABLE[name] = Entry(name, kind, target, runner)


def unregister(name: str) -> None:
    """Remove a method added by :func:`register`."""
    del _TABLE[name]


@contextmanager
def registered(name: str, kind: Kind, target: str | type) -> Iterator[None]:
    """:func:`register` for the duration of a block."""
    register(name, kind, target)
    try:
        yield
    finally:
        unregister(name)


__all__ = ["Entry", "EXACT", "DEFAULT_STEP", "REFERENCE_ADAPTIVE", "REFERENCE_STEP", "names", "entry",
           "implementation", "classes", "integrator_classes", "method", "methods", "planned", "PEERS_ONLY", "COMPILED_PEER", "register",
           "unregister", "registered"]
