"""The one protocol every simulation method follows, its declared traits and the run options.

A :class:`Method` says why it does not apply to a system (:meth:`Method.refusal`, None when it
does) and runs from an initial state onto a :class:`~.grid.Grid`, handing the recorded frames to a
:class:`~.recorder.Recorder` (:meth:`Method.run`). Three kinds implement it (:class:`Kind`):
the exact solution (:mod:`.exact`), fixed-step integrators (:mod:`.step`) and tolerance-driven
adaptive methods (:mod:`.adaptive`). Methods are made by :mod:`.registry` from their names.
"""

from __future__ import annotations

import abc
import enum
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

from ..errors import RunRefused

if TYPE_CHECKING:  # pragma: no cover  (listing method names imports no NumPy)
    import numpy as np

    from ..system import System
    from .grid import Grid
    from .recorder import Recorder

#: Default tolerances of the adaptive methods (``simulate``'s ``rtol``/``atol``).
DEFAULT_RTOL = 1e-10
DEFAULT_ATOL = 1e-12


class Kind(enum.Enum):
    """The three kinds of method."""

    EXACT = "exact"
    STEP = "step"
    ADAPTIVE = "adaptive"


class SpectrumSource(enum.StrEnum):
    """Where the exact solution takes its modes from: the spring-factor SVD (accurate) or the
    generated module's closed forms."""

    SVD = "svd"
    CLOSED_FORM = "closed-form"


@dataclass(frozen=True)
class Traits:
    """What a method declares about itself (fed to the error models and the planner).

    Attributes
    ----------
    order : float
        Global order; ``math.inf`` for exact solutions and exact propagators.
    symplectic : bool
    evals_per_step : float
        Force evaluations per step (NaN for adaptive methods: counted per run).
    stability_limit : float
        Largest stable ``ω_max·h`` on a linear chain; ``math.inf`` for any step.
    supports_damping : bool
        Integrates velocity-dependent forces itself (otherwise a splitting wraps it, or it refuses).
    """

    order: float
    symplectic: bool
    evals_per_step: float = math.nan
    stability_limit: float = math.inf
    supports_damping: bool = True

    @classmethod
    def of(cls, implementation: type) -> "Traits":
        """The traits an implementation class declares (its class attributes; the defaults above
        for those it leaves out)."""
        c = implementation
        return cls(order=float(c.order), symplectic=bool(c.symplectic),
                   evals_per_step=float(getattr(c, "evals_per_step", math.nan)),
                   stability_limit=float(getattr(c, "stability_limit", math.inf)),
                   supports_damping=bool(getattr(c, "supports_damping", True)))


@dataclass(frozen=True)
class Options:
    """Settings of a run that are not the grid: tolerances, the exact solution's spectrum, progress.

    Attributes
    ----------
    rtol, atol : float
        Tolerances of adaptive methods.
    spectrum : SpectrumSource
    progress : bool or None
        Progress on stderr for phases longer than about a second (None: on).
    settings : tuple of (str, float)
        Named settings of the methods that take them (:attr:`Method.takes`; e.g. HHT-α's
        ``alpha``), sorted by name; a dict is accepted.
    compiled : bool
        Run small ``[masses]`` scenes' fixed-step methods as one compiled loop
        (:mod:`numeric.compiled`) where one applies; False: always the NumPy driver.
    """

    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL
    spectrum: SpectrumSource = SpectrumSource.SVD
    progress: bool | None = None
    settings: tuple = ()
    compiled: bool = True

    def __post_init__(self):
        items = self.settings.items() if isinstance(self.settings, dict) else self.settings
        object.__setattr__(self, "settings", tuple(sorted(items)))
        try:
            object.__setattr__(self, "spectrum", SpectrumSource(self.spectrum))
        except ValueError:
            raise RunRefused(f"spectrum {self.spectrum!r}: accepted: "
                             + " or ".join(repr(s.value) for s in SpectrumSource), quantity="spectrum") from None


@dataclass(frozen=True)
class Method(abc.ABC):
    """A way to compute a trajectory.

    Attributes
    ----------
    name : str
        The name at the edge (command line, NPZ keys, records).
    options : Options
    implementation : type or None
        The class that does the work (an integrator or an adaptive solver), whose declared
        :class:`Traits` are the method's.
    """

    name: str
    options: Options = field(default=Options(), compare=False)
    implementation: type | None = None

    #: Which kind of method this is (declared by each kind).
    kind: ClassVar[Kind]

    @property
    def traits(self) -> Traits:
        """The declared traits (the implementation's)."""
        return Traits.of(self.implementation)

    @property
    def takes(self) -> tuple[str, ...]:
        """Names of the :attr:`Options.settings` this method reads (none by default)."""
        return ()

    def refusal(self, system: "System") -> str | None:
        """Why this method does not apply to ``system`` (None when it does)."""
        return None

    def check(self, system: "System") -> None:
        """Raise :class:`~numeric.errors.RunRefused` naming the method when it does not apply."""
        why = self.refusal(system)
        if why:
            raise RunRefused(f"method {self.name!r}: {why}", quantity="method")

    def with_options(self, options: Options) -> "Method":
        """The same method with other options."""
        from dataclasses import replace

        return replace(self, options=options)

    @abc.abstractmethod
    def run(self, system: "System", x0: "np.ndarray", v0: "np.ndarray", grid: "Grid",
            recorder: "Recorder") -> int:
        """Compute the frames of ``grid`` from ``(x0, v0)`` (shape (N,)) into ``recorder``.

        Returns the number of force evaluations (0 for exact solutions).
        """


@dataclass(frozen=True)
class Recorded:
    """A run kept in memory: ``t`` (S,), ``x``, ``v`` (S, N) and the force evaluations."""

    t: "np.ndarray" = field(repr=False)
    x: "np.ndarray" = field(repr=False)
    v: "np.ndarray" = field(repr=False)
    force_evals: int


def record(method: Method, system: "System", x0: np.ndarray, v0: np.ndarray, grid: "Grid") -> Recorded:
    """``method.run`` into a :class:`MemoryRecorder`: what plan, bench and references time and measure."""
    from .recorder import MemoryRecorder

    rec = MemoryRecorder(grid.frames, system.n)
    evals = method.run(system, x0, v0, grid, rec)
    return Recorded(grid.t, rec.x, rec.v, int(evals))


__all__ = ["Kind", "Traits", "Options", "Method", "SpectrumSource", "Recorded", "record", "DEFAULT_RTOL",
           "DEFAULT_ATOL"]
