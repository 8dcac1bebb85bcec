"""Fused velocity-Verlet steps for ``[chain]`` modules: one pass over memory per step.

A generated chain module (:mod:`derive.chain`) evaluates its acceleration
with NumPy slices, one ufunc (one pass over memory) at a time; a Verlet step
built on it makes about ten passes. Here the whole step is one sweep over
the chain in cache-sized blocks of rows: a block is drifted
(``x ← x + h v + h²/2 a``) and then the rows whose three neighbours are all
drifted are kicked (``a' = a(x)``, ``v ← v + h/2 (a + a')``), so each row
of ``x``, ``v`` and ``a`` leaves main memory once and comes back once.

Two sweeps are provided:

* :meth:`FusedVerlet.step` — one velocity-Verlet step on ``(x, v, a)``
  (the :class:`~numeric.integrators.base.Integrator` kernel contract; reads
  and writes 24 bytes per mass, 48 in all, one stencil per mass).
* :meth:`FusedVerlet.advance` — many steps in the equivalent "half-step
  velocity" form ``w = v + h/2 a``: ``x ← x + h w;  w ← w + h a(x)``. The
  state in memory is ``(x, w)``: 16 bytes read and 16 written per mass and
  sweep — the 32-byte-per-mass floor — and one stencil per mass and step.
  Open chains (free or wall ends) make two steps per sweep (a two-stage
  wavefront over each cached block), so memory traffic per step halves and
  the step is bound by arithmetic, not memory. ``v`` and ``a`` are restored
  at the end (three extra passes per call), so the result is velocity
  Verlet to rounding.

The compiled path needs numba (the optional ``fast`` extra); it is imported
lazily, and without it the same API runs plain NumPy on the module's own
stencil (:data:`Backend.NUMPY`), which is also what the tests compare with.

Chain ends follow the generated modules: ``free``, ``wall`` (a spring
``k(-1)`` to a wall on the left, ``k(n-1)`` on the right) or ``ring`` (the
spring ``k(n-1)`` closes n-1 to 0); masses and springs may depend on the
index (then read from arrays) and springs may be cubic (``k d + k3 d³``) or any potential
``V(d)`` whose law is free of the index: its tension ``V'(d)``, compiled from the generated
module's ``spring_force`` (:mod:`numeric.compiled.potential_law`), takes the cubic term's place.
"""

import enum
import math
from dataclasses import dataclass, field
from types import ModuleType
from typing import Callable

import numpy as np

from ...generated.contract import End
from ..system import System, interface
from ..errors import RunRefused
from .fast_coefficients import ChainCoefficients
from .fast_kernels import BLOCK_ELEMENTS, compiled_kernels, SweepMode, available, stream_update


class Backend(enum.Enum):
    """How a step is computed."""

    NUMBA = "numba"  #: fused compiled sweep (needs numba)
    NUMPY = "numpy"  #: the module's NumPy stencil, one ufunc pass at a time


def default_backend() -> Backend:
    """:data:`Backend.NUMBA` when numba is available, else :data:`Backend.NUMPY`."""
    return Backend.NUMBA if available() else Backend.NUMPY


# -- the public object ----------------------------------------------------------------------
def _flat(arr: np.ndarray, n: int, name: str) -> tuple[np.ndarray, int]:
    """A flat float64 C-contiguous view of a (n,) or (n, B) array, and B."""
    if not (isinstance(arr, np.ndarray) and arr.dtype == np.float64 and arr.flags.c_contiguous):
        raise ValueError(f"{name}: need a C-contiguous float64 ndarray, got "
                         f"{type(arr).__name__} {getattr(arr, 'dtype', '')}")
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise ValueError(f"{name}: need shape ({n},) or ({n}, B), got {arr.shape}")
    nb = 1 if arr.ndim == 1 else arr.shape[1]
    if nb < 1:
        raise ValueError(f"{name}: empty batch, shape {arr.shape}")
    return arr.reshape(-1), nb


@dataclass(frozen=True)
class FusedVerlet:
    """Velocity Verlet with step ``h`` on one chain, fused (numba) or on NumPy.

    Build with :meth:`from_module`. States are float64 C-contiguous arrays of
    shape (n,) or (n, B).
    """

    coefficients: ChainCoefficients
    acceleration: Callable[[np.ndarray], np.ndarray] = field(repr=False)
    h: float
    backend: Backend

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None = None, n: int | None = None,
                    h: float = 1.0, backend: Backend | None = None) -> "FusedVerlet":
        """Bind a generated ``[chain]`` module, parameters, size and step.

        Parameters
        ----------
        backend : Backend, optional
            Default: :func:`default_backend` (numba if it loads).
        """
        h = float(h)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"step size h must be finite and > 0, got {h!r}")
        if n is not None and int(n) < 1:
            raise ValueError(f"a chain needs n >= 1 masses, got {n}")
        if not interface(module).chain:
            raise RunRefused("the fused chain step needs a [chain] scene's generated module")
        return cls.from_system(System.from_module(module, params, n=n), h, backend)

    @classmethod
    def from_system(cls, system: System, h: float = 1.0, backend: Backend | None = None) -> "FusedVerlet":
        """Bind a ``[chain]`` :class:`System` (its size and parameter values) and a step (see :meth:`from_module`)."""
        h = float(h)
        if not (math.isfinite(h) and h > 0):
            raise ValueError(f"step size h must be finite and > 0, got {h!r}")
        coeffs = ChainCoefficients.from_system(system)
        law_missing = system.potential and coeffs.law is None  # an index-dependent potential
        if backend is None:
            backend = Backend.NUMPY if law_missing else default_backend()
        if backend is Backend.NUMBA and law_missing and available():
            raise RunRefused("the fused chain step compiles index-free spring potentials only; this chain's "
                             "potential depends on i: use the NumPy backend")
        if backend is Backend.NUMBA and not available():
            raise RunRefused("the fused chain step needs numba: install the `fast` extra "
                             "(pip install 'springchain[fast]') or use the NumPy backend")
        return cls(coeffs, system.make_acceleration(), h, backend)

    @property
    def n(self) -> int:
        return self.coefficients.n

    def _numpy_force(self, x: np.ndarray) -> np.ndarray:
        """The module's stencil; a 1-D state goes through as (n, 1), the generated modules' state shape."""
        if x.ndim == 1:
            return self.acceleration(x[:, None])[:, 0]
        return self.acceleration(x)

    def _kernels(self):
        law = self.coefficients.law
        k = compiled_kernels() if law is None else law.kernels
        return k.force, k.sweep, k.half_kick

    # -- building blocks ------------------------------------------------------------------
    def force(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The acceleration a(x); x shape (n,) or (n, B) -> same shape (written into ``out`` if given)."""
        if self.backend is Backend.NUMPY:
            a = self._numpy_force(x)
            if out is None:
                return a
            out[...] = a
            return out
        xf, nb = _flat(x, self.n, "x")
        out = np.empty_like(x) if out is None else out
        af, _ = _flat(out, self.n, "out")
        self._kernels()[0](xf, af, nb, *self.coefficients.kernel_args())
        return out

    def step(self, x: np.ndarray, v: np.ndarray, a: np.ndarray, *,
             inplace: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One velocity-Verlet step from the state (x, v) with a = a(x).

        Parameters
        ----------
        x, v, a : ndarray, shape (n,) or (n, B)
        inplace : bool
            Update the given arrays and return them (no allocation). Otherwise
            the inputs are left untouched and new arrays are returned.

        Returns
        -------
        x, v, a : ndarray
            The state one step later and the acceleration there.
        """
        h = self.h
        if self.backend is Backend.NUMPY:
            xn = x + h * v + (0.5 * h * h) * a
            an = self._numpy_force(xn)
            vn = v + (0.5 * h) * (a + an)
            if not inplace:
                return xn, vn, an
            x[...], v[...], a[...] = xn, vn, an
            return x, v, a
        xf, nb = _flat(x, self.n, "x")
        vf, _ = _flat(v, self.n, "v")
        af, _ = _flat(a, self.n, "a")
        if inplace:
            xo, vo, ao = x, v, a
            xof, vof, aof = xf, vf, af
        else:
            xo, vo, ao = np.empty_like(x), np.empty_like(v), np.empty_like(a)
            xof, vof, aof = xo.reshape(-1), vo.reshape(-1), ao.reshape(-1)
        self._kernels()[1](xf, vf, af, xof, vof, aof, inplace, nb, *self.coefficients.kernel_args(), h,
                           int(SweepMode.VERLET), 1, False)
        return xo, vo, ao

    def advance(self, x: np.ndarray, v: np.ndarray, a: np.ndarray, steps: int, *,
                two_step_sweeps: bool = True) -> tuple[np.ndarray, ...]:
        """``steps`` velocity-Verlet steps in place, through the half-step velocity ``w = v + h/2 a``.

        Equal to ``steps`` calls of :meth:`step` up to rounding. Each sweep
        moves 32 bytes per mass (x and w in and out) and makes one step, or
        two on an open chain (free or wall ends) unless ``two_step_sweeps`` is
        False. Updates and returns x, v, a.
        """
        steps = int(steps)
        if steps < 0:
            raise ValueError(f"steps must be >= 0, got {steps}")
        if steps == 0:
            return x, v, a
        h = self.h
        if self.backend is Backend.NUMPY:
            v += (0.5 * h) * a
            for _ in range(steps):
                x += h * v
                v += h * self._numpy_force(x)
            a[...] = self._numpy_force(x)
            v -= (0.5 * h) * a
            return x, v, a
        xf, nb = _flat(x, self.n, "x")
        vf, _ = _flat(v, self.n, "v")
        af, _ = _flat(a, self.n, "a")
        force, sweep, half_kick = self._kernels()
        args = self.coefficients.kernel_args()
        half_kick(vf, af, 0.5 * h)
        sweep(xf, vf, af, xf, vf, af, True, nb, *args, h, int(SweepMode.LEAPFROG), steps, bool(two_step_sweeps))
        force(xf, af, nb, *args)
        half_kick(vf, af, -0.5 * h)
        return x, v, a

    # -- the integrator contract -------------------------------------------------------------
    def kernel(self, *, inplace: bool = False) -> Callable:
        """A step function ``(x, v, a, i) -> (x, v, a)`` (:data:`numeric.integrators.base.StepKernel`).

        With ``inplace=False`` (the contract's default) inputs are never
        modified; with ``inplace=True`` they are updated and returned, which
        is safe for a driver that copies the frames it records (the attribute
        ``inplace`` on the returned function says which). An in-place kernel
        also carries ``advance(x, v, a, steps)`` (:meth:`advance`), which a
        driver may call between recorded frames instead of ``steps`` kernel calls.
        """
        def step(x, v, a, i):
            return self.step(x, v, a, inplace=inplace)

        step.inplace = inplace
        step.backend = self.backend
        if inplace:  # many steps at once, for a driver that records only every k-th step
            step.advance = self.advance
        return step


def chain_verlet_kernel(module: ModuleType, params: dict[str, float] | None, n: int | None, h: float, *,
                        inplace: bool = False, backend: Backend | None = None) -> Callable:
    """Velocity-Verlet step kernel ``(x, v, a, i) -> (x, v, a)`` for a ``[chain]`` module.

    Compatible with :meth:`numeric.integrators.base.Integrator.kernel` for a
    conservative chain (no dampers, no external forces). x, v, a have shape
    (n, B) or (n,), float64, C-contiguous.
    """
    return FusedVerlet.from_module(module, params, n, h, backend).kernel(inplace=inplace)


def chain_verlet_advance(module: ModuleType, params: dict[str, float] | None, n: int | None, h: float, *,
                         backend: Backend | None = None) -> Callable:
    """``advance(x, v, a, steps) -> (x, v, a)``: many Verlet steps in place at the 32-byte floor."""
    return FusedVerlet.from_module(module, params, n, h, backend).advance


#: Chains with at least this many masses evaluate a potential's forces through the compiled kernel in
#: every step method (below it the module's NumPy stencil is as fast, and needs no compiling).
COMPILED_FORCE_MIN_N = 1 << 14


def compiled_acceleration(system: System):
    """``a(x)`` of a potential chain through the compiled kernel (x shape (n,) or (n, B)), for the
    step methods other than Verlet; None below :data:`COMPILED_FORCE_MIN_N` masses, without numba or
    for an index-dependent law."""
    if (not system.chain or system.n < COMPILED_FORCE_MIN_N or not system.potential or system.law_indexed
            or not available()):
        return None
    fv = FusedVerlet.from_system(system, 1.0, Backend.NUMBA)

    def acceleration(x):
        return fv.force(np.ascontiguousarray(x, dtype=np.float64))

    return acceleration


def acceleration_of(system) -> Callable[[np.ndarray], np.ndarray]:
    """The conservative acceleration a(x) the step and adaptive methods evaluate: a long chain with an
    index-free spring potential through its compiled law (:func:`compiled_acceleration`), every other
    system through :attr:`System.acceleration_fn`."""
    if system.chain and system.potential:
        fast = compiled_acceleration(system)
        if fast is not None:
            return fast
    return system.acceleration_fn


__all__ = ["Backend", "End", "ChainCoefficients", "FusedVerlet", "available", "default_backend",
           "chain_verlet_kernel", "chain_verlet_advance", "stream_update", "BLOCK_ELEMENTS",
           "COMPILED_FORCE_MIN_N", "compiled_acceleration", "acceleration_of"]
