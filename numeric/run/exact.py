"""The exact solution as a method, and the one place that chooses its solver.

:func:`solve` picks, from what the system is (:class:`~numeric.system.System`):

* springs only, ``[chain]``: the chain's sine/cosine/Fourier transform (uniform chains, O(N log N)
  per output time, no N × N) or its eigenvectors (index-dependent, up to ``MAX_DENSE`` masses),
  :mod:`numeric.exact.chain`;
* springs only, ``[masses]``: the modal solution (:mod:`numeric.exact.modal`) from the accurate spectrum
  (the spring-factor SVD) or the generated closed forms;
* dampers, forces, gravity, ground: the augmented matrix exponential (:mod:`numeric.exact.linear`).

Whether one applies at all, and why not, is :attr:`System.no_exact_solution`. Plan and bench
time and measure against these same solutions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import RunRefused
from ..progress import Reporter, phase
from ..modes.spectrum import Spectrum, spectrum_from_closed_form
from ..system import System
from .grid import Grid
from .protocol import Kind, Method, SpectrumSource, Traits
from .recorder import Recorder

#: Frames per block when the modal solution is evaluated into a recorder (bounded memory).
EXACT_BLOCK_BYTES = 64 * 2**20


def spectrum_of(system: System, source: SpectrumSource = SpectrumSource.SVD) -> Spectrum:
    """The system's modes: the accurate spring-factor SVD (computed once per system) or the generated
    module's closed forms (:func:`closed_form_spectrum`)."""
    if SpectrumSource(source) is SpectrumSource.CLOSED_FORM:
        return closed_form_spectrum(system)
    return system.spectrum


def closed_form_spectrum(system: System) -> Spectrum:
    """The generated module's ω² and shapes (closed forms where they are cancellation-free, else
    its own spring-factor route), or a one-line refusal naming the first mode that is not finite,
    not ≥ 0, or a rigid mode that is not exactly 0 (e.g. parameter values beyond float range)."""
    n, rigid = system.masses.shape[0], system.rigid_modes
    try:
        with np.errstate(all="ignore"):
            w2 = system.omega2()
            shapes = system.mode_shapes()
    except (FloatingPointError, ArithmeticError, np.linalg.LinAlgError) as exc:
        raise RunRefused(f"spectrum 'closed-form': the modes cannot be evaluated to float64 accuracy at these "
                         f"parameter values ({exc}); accepted: spectrum 'svd'", quantity="spectrum") from None
    if w2.shape != (n,) or shapes.shape != (n, n):
        raise RunRefused(f"spectrum 'closed-form': the generated module returned {w2.shape[0]} modes for {n} "
                         f"masses; accepted: spectrum 'svd'", quantity="spectrum")
    order = np.argsort(w2, kind="stable")
    ws = w2[order].tolist()  # a few scalar tests (this is on the exact method's timed path)
    fine = (bool(np.isfinite(w2).all() and np.isfinite(shapes).all()) and all((shapes != 0.0).any(axis=0).tolist())
            and all(w >= 0 and (pos < rigid) == (w == 0.0) for pos, w in enumerate(ws)))  # NaN fails w >= 0
    if not fine:  # name the first mode (in ascending order) that is not right
        ss = shapes[:, order]
        bad = (~np.isfinite(w2[order]) | ~np.isfinite(ss).all(axis=0) | (w2[order] < 0)
               | ((np.arange(n) < rigid) != (w2[order] == 0.0)) | ~ss.any(axis=0))
        j = int(order[int(np.argmax(bad))])
        raise RunRefused(f"spectrum 'closed-form': mode {j} (omega2 = {w2[j]:.17g}) cannot be evaluated to "
                         f"float64 accuracy at these parameter values; accepted: spectrum 'svd'",
                         quantity="spectrum")
    return spectrum_from_closed_form(w2, shapes, system.masses, rigid)


@dataclass(frozen=True)
class Solution:
    """An exact solution set up from one initial state: ``at(t) -> (x, v)``, shapes (S, N), for
    increasing times ``t`` (a uniform grid, possibly with a shorter last interval)."""

    description: str
    evaluate: object = field(repr=False)
    #: Evaluate one time at a time (long chains: every frame costs O(N log N), no (S, N) block).
    per_frame: bool = False
    #: Evaluate every time in one call (a solution that propagates from the first time onwards).
    whole: bool = False

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, v = self.evaluate(np.asarray(t, dtype=float))
        return np.asarray(x), np.asarray(v)

    def record(self, grid: Grid, recorder: Recorder, n: int, progress: bool | None = None) -> None:
        """Evaluate on ``grid`` into ``recorder`` (blocks of bounded size, or frame by frame)."""
        t = grid.t
        if self.per_frame:
            bar = Reporter("exact solution", t.shape[0], enabled=progress)
            for row in range(t.shape[0]):
                x, v = self.at(t[row:row + 1])
                recorder.frames(row, x, v)
                bar.update(row + 1)
            return
        block = t.shape[0] if self.whole else max(1, EXACT_BLOCK_BYTES // (16 * max(n, 1)))
        for start in range(0, t.shape[0], block):
            x, v = self.at(t[start:start + block])
            recorder.frames(start, x, v)


def solve(system: System, x0: np.ndarray, v0: np.ndarray,
          source: SpectrumSource = SpectrumSource.SVD) -> Solution:
    """Set up the exact solution of ``system`` from ``(x0, v0)`` (shape (N,)): the one choice of solver.

    Raises
    ------
    RunRefused
        When no exact solution applies (:attr:`System.no_exact_solution`).
    """
    why = system.no_exact_solution
    if why:
        raise RunRefused(f"no exact solution applies ({why})", quantity="method")
    x0, v0 = np.asarray(x0, dtype=float), np.asarray(v0, dtype=float)
    if system.springs_only and system.chain:
        from ..exact.chain import ChainModal

        sol = ChainModal.from_system(system, x0, v0)
        return Solution("exact: the chain's transform solution (numeric.exact.chain), float64", sol.at, True)
    if system.springs_only:
        from ..exact.modal import ModalSolution

        modal = ModalSolution.from_initial(spectrum_of(system, source), x0, v0)
        return Solution(f"exact: modal solution ({SpectrumSource(source).value} spectrum), float64", modal.at)
    from ..exact.linear import AugmentedLinear

    aug = AugmentedLinear.from_system(system)

    def evaluate(t):  # a uniform grid, possibly with a shorter last interval
        return aug.solve_grid(x0, v0, t)

    return Solution("exact: augmented matrix exponential (numeric.exact.linear), float64", evaluate, whole=True)


@dataclass(frozen=True)
class ExactSolution(Method):
    """The exact solution (see :func:`solve`); any step, no force evaluations."""

    kind: ClassVar[Kind] = Kind.EXACT

    @property
    def traits(self) -> Traits:
        return Traits(order=math.inf, symplectic=True, evals_per_step=0.0)

    def refusal(self, system: System) -> str | None:
        why = system.no_exact_solution
        if why is None:
            return None
        from . import registry

        return f"no exact solution applies ({why}); use one of {', '.join(registry.names(Kind.STEP))}"

    def prepare(self, system: System, x0: np.ndarray, v0: np.ndarray) -> Solution:
        """The set-up half of :meth:`run`: the solution from ``(x0, v0)``, ready to record any grid."""
        self.check(system)
        with phase("exact solution: set-up", enabled=self.options.progress):
            return solve(system, x0, v0, self.options.spectrum)

    def run(self, system, x0, v0, grid, recorder) -> int:
        self.prepare(system, x0, v0).record(grid, recorder, system.n, self.options.progress)
        return 0


__all__ = ["ExactSolution", "Solution", "solve", "spectrum_of", "closed_form_spectrum"]
