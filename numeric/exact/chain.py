"""The exact solution of a uniform linear chain by fast transforms: O(N log N) per output time.

The normal modes of a uniform chain (masses m, springs k) are known in
closed form (:mod:`derive.chain`), and each family is the basis of a fast
real transform, so modal coordinates are one transform away and no N×N
matrix is ever formed:

==========  ===========================================  ==============================================
ends        shapes (i = 0 … n−1)                          ω_j / (2√(k/m)), transform
==========  ===========================================  ==============================================
free–free   cos(jπ(i + ½)/n), j = 0 … n−1                 sin(jπ/(2n));  DCT-II (orthonormal)
wall–wall   sin((j+1)π(i+1)/(n+1)), j = 0 … n−1           sin((j+1)π/(2(n+1)));  DST-I (orthonormal)
wall–free   sin((2j+1)π(i+1)/(2n+1)), j = 0 … n−1         sin((2j+1)π/(2(2n+1)));  DST-I of size 2n, odd
            (free–wall: the same with i counted from the  outputs (see below)
            right end)
ring        exp(2πi·j·l/n), j = 0 … ⌊n/2⌋ (real FFT)       |sin(jπ/n)|;  rFFT
==========  ===========================================  ==============================================

The frequencies themselves are not written here: they come from the generated
module's ``mode_omega()`` (the closed forms live once, in :mod:`derive.chain`);
the table records which transform diagonalises each family and in which order.

Wall–free has no standard transform of its own (the denominator 2n + 1 is
odd); it is embedded in a DST-I of size 2n, whose kernel is
``sin(π(k+1)(l+1)/(2n+1))``: zero-pad x to 2n entries and keep the outputs
with k = 2j (odd k + 1 = 2j + 1). The inverse puts q_j at k = 2j, zeros in
between, and keeps the first n outputs. Both are scaled by ``1/√(2n+1)``
(the shapes have squared norm (2n+1)/4).

Each mode then evolves exactly, ``q(t) = q0 cos(ωt) + q̇0·t·sinc(ωt)``
(:func:`numeric.exact.modal.tsinc`), never dividing by ω, so the rigid-body mode
of a free chain or a ring (ω = 0 exactly: sin 0) is the uniform drift.

Index-dependent chains have no closed form: for them this module falls back
to the modes of the bidiagonal spring factor (:mod:`numeric.modes.chain`: ω by bisection,
the values ``modes`` prints, vectors by LAPACK ``dbdsqr``, both relatively accurate; O(N³)
set-up, O(N²) memory; refused above :data:`MAX_FALLBACK` masses), and rings to the dense
spectrum (:mod:`numeric.modes.spectrum`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from types import ModuleType

import numpy as np
import scipy.fft

from ...generated.contract import MAX_DENSE, End
from ..system import System, interface
from ..errors import RunRefused
from .modal import tsinc
from .sine_transform import dst1

#: Largest index-dependent chain solved through its (dense) eigenvectors.
MAX_FALLBACK = MAX_DENSE


class Basis(enum.Enum):
    """How modal coordinates are computed."""

    DCT = "free-free: DCT-II"
    DST = "wall-wall: DST-I"
    DST_ODD = "wall-free: DST-I of size 2n, odd outputs"
    FFT = "ring: real FFT"
    EIGENVECTORS = "index-dependent: eigenvectors (bidiagonal spring factor, or the dense SVD for a ring)"

    @property
    def fast(self) -> bool:
        """An O(N log N) transform (no stored eigenvectors)."""
        return self is not Basis.EIGENVECTORS


def basis_of(left: End, right: End) -> Basis:
    """The transform that diagonalises a uniform chain with these ends (free–wall: reversed wall–free)."""
    if left is End.RING:
        return Basis.FFT
    if left is End.FREE and right is End.FREE:
        return Basis.DCT
    if left is End.WALL and right is End.WALL:
        return Basis.DST
    return Basis.DST_ODD


def forward_transform(basis: Basis, x: np.ndarray) -> np.ndarray:
    """Modal coordinates of x (axis 0)."""
    n = x.shape[0]
    if basis is Basis.DCT:
        return scipy.fft.dct(x, type=2, norm="ortho", axis=0)
    if basis is Basis.DST:
        return dst1(x, axis=0)
    if basis is Basis.FFT:
        return scipy.fft.rfft(x, axis=0)
    pad = np.zeros((2 * n,) + x.shape[1:])
    pad[:n] = x
    return np.sqrt(2.0) * dst1(pad, axis=0)[0::2]


def _inverse(basis: Basis, q: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Positions from modal coordinates along ``axis``."""
    if basis is Basis.DCT:
        return scipy.fft.idct(q, type=2, norm="ortho", axis=axis)
    if basis is Basis.DST:
        return dst1(q, axis=axis)  # orthonormal DST-I: its own inverse
    if basis is Basis.FFT:
        return scipy.fft.irfft(q, n=n, axis=axis)
    q = np.moveaxis(q, axis, 0)
    pad = np.zeros((2 * n,) + q.shape[1:])
    pad[0::2] = q
    x = np.sqrt(2.0) * dst1(pad, axis=0)[:n]
    return np.moveaxis(x, 0, axis)


@dataclass(frozen=True)
class ChainModal:
    """Exact trajectory of a linear ``[chain]`` from (x0, v0).

    Build with :meth:`from_module` (or :meth:`uniform`); evaluate with :meth:`at`.

    Attributes
    ----------
    basis : Basis
    n : int
    omega : ndarray
        Frequencies in the order of the modal coordinates (not sorted).
    reverse : bool
        The wall is on the right (free–wall): index counted from the right end.
    """

    basis: Basis
    n: int
    omega: np.ndarray = field(repr=False)
    q0: np.ndarray = field(repr=False)
    p0: np.ndarray = field(repr=False)
    reverse: bool = False
    vectors: np.ndarray | None = field(default=None, repr=False)
    sqrt_mass: np.ndarray | None = field(default=None, repr=False)

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def transform(cls, mode_omega: np.ndarray, left: End | str, right: End | str, x0: np.ndarray,
                  v0: np.ndarray) -> "ChainModal":
        """The transform solution of a uniform chain of len(x0) masses.

        Parameters
        ----------
        mode_omega : ndarray, shape (n,)
            Angular frequencies in mode-index order, as a generated uniform chain module's
            ``mode_omega()`` returns them (the closed forms are written once, in :mod:`derive.chain`).
        left, right : End or its word
        x0, v0 : ndarray, shape (n,) or (n, B)
        """
        x0, v0 = _initial(x0, v0)
        try:
            left, right = End(left), End(right)
        except ValueError:
            raise ValueError(f"chain ends must be free/wall on each side or ring on both, got {str(left)!r}, {str(right)!r}") from None
        if (left is End.RING) != (right is End.RING):
            raise ValueError(f"chain ends must be free/wall on each side or ring on both, got {str(left)!r}, {str(right)!r}")
        n = x0.shape[0]
        omega = np.asarray(mode_omega, dtype=float)
        if omega.shape != (n,):
            raise ValueError(f"mode_omega: need shape ({n},), got {omega.shape}")
        basis = basis_of(left, right)
        if basis is Basis.FFT:
            omega = omega[: n // 2 + 1]  # one frequency per rFFT coefficient (j and n - j coincide)
        reverse = left is End.FREE and right is End.WALL
        if reverse:
            x0, v0 = x0[::-1], v0[::-1]
        return cls(basis, n, omega, forward_transform(basis, x0), forward_transform(basis, v0), reverse)

    @classmethod
    def from_module(cls, module: ModuleType, params: dict[str, float] | None, x0: np.ndarray,
                    v0: np.ndarray) -> "ChainModal":
        """The exact solution for a generated ``[chain]`` module's linear chain of len(x0) masses.

        A uniform chain uses its transform; an index-dependent one falls back
        to eigenvectors (the bidiagonal spring factor; the dense SVD for a ring) up to
        :data:`MAX_FALLBACK` masses.
        """
        facts = interface(module)
        if not facts.chain:
            raise RunRefused("ChainModal needs a [chain] scene's generated module; use numeric.exact.modal for others")
        if not facts.linear:
            raise RunRefused("no exact solution: this chain has cubic springs or spring potentials "
                             "(use an integrator, e.g. verlet)")
        x0, v0 = _initial(x0, v0)
        return cls.from_system(System.from_module(module, params, n=x0.shape[0]), x0, v0)

    @classmethod
    def from_system(cls, system: System, x0: np.ndarray, v0: np.ndarray) -> "ChainModal":
        """The exact solution of a linear ``[chain]`` :class:`System` of len(x0) masses (see :meth:`from_module`)."""
        if not system.chain:
            raise RunRefused("ChainModal needs a [chain] scene's generated module; use numeric.exact.modal for others")
        if not system.linear:
            raise RunRefused("no exact solution: this chain has cubic springs or spring potentials "
                             "(use an integrator, e.g. verlet)")
        x0, v0 = _initial(x0, v0)
        n = x0.shape[0]
        system = system.with_n(n)
        if system.has("mode_omega"):
            left, right = system.ends
            return cls.transform(system.mode_omega(), left, right, x0, v0)
        if n > MAX_FALLBACK:
            raise RunRefused(f"index-dependent chain of n = {n} masses: no closed-form modes, and the "
                             f"eigenvector fallback is limited to n <= {MAX_FALLBACK}; use method 'verlet'", quantity="method")
        return cls._eigenvectors(system, x0, v0)

    @classmethod
    def _eigenvectors(cls, system: System, x0, v0) -> "ChainModal":
        masses, ends, ks = system.masses, system.spring_ends, system.stiffness
        n = masses.shape[0]
        r = np.sqrt(masses)
        if system.ends[0] is End.RING:
            from ..modes.spectrum import spectrum

            spec = spectrum(masses, ends, ks)
            omega, E = spec.omega, spec.vectors
        else:  # the bidiagonal spring factor: ω by bisection (the printed values), vectors by dbdsqr
            from ..modes.chain import chain_spectrum

            spec = chain_spectrum(masses, ends, ks)
            omega, E = spec.omega, spec.vectors
        shape = (-1,) + (1,) * (x0.ndim - 1)
        rr = r.reshape(shape)
        q0 = np.tensordot(E.T, rr * x0, axes=1)
        p0 = np.tensordot(E.T, rr * v0, axes=1)
        return cls(Basis.EIGENVECTORS, n, omega, q0, p0, False, E, r)

    # -- evaluation ------------------------------------------------------------------------------
    def modal_at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Modal coordinates and their rates at times t: shape (S, modes, ...) or (modes, ...)."""
        t = np.asarray(t, dtype=float)
        extra = (1,) * (self.q0.ndim - 1)
        tt = t.reshape(t.shape + (1,) + extra)
        w = self.omega.reshape(self.omega.shape + extra)
        c = np.cos(w * tt)
        s = tsinc(w, tt)
        q = self.q0 * c + self.p0 * s
        p = self.p0 * c - self.q0 * (w * w) * s
        return q, p

    def at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at times ``t`` (a float, or an array of shape (S,)): x and v of
        shape (n, ...), or (S, n, ...) for an array of times, as :meth:`numeric.exact.modal.ModalSolution.at`."""
        t = np.asarray(t, dtype=float)
        q, p = self.modal_at(t)
        axis = t.ndim
        if self.basis is Basis.EIGENVECTORS:
            extra = (1,) * (self.q0.ndim - 1)
            r = self.sqrt_mass.reshape((-1,) + extra)
            x = np.moveaxis(np.tensordot(self.vectors, q, axes=([1], [axis])), 0, axis) / r
            v = np.moveaxis(np.tensordot(self.vectors, p, axes=([1], [axis])), 0, axis) / r
            return x, v
        x = _inverse(self.basis, q, self.n, axis)
        v = _inverse(self.basis, p, self.n, axis)
        if self.reverse:
            x, v = np.flip(x, axis), np.flip(v, axis)
        return np.ascontiguousarray(x), np.ascontiguousarray(v)

    @property
    def omega_sorted(self) -> np.ndarray:
        """All n frequencies ascending (a ring's 0 < j < n/2 counted twice, once per shape)."""
        if self.basis is Basis.FFT:
            j = np.arange(self.n)
            w = self.omega[np.minimum(j, self.n - j)]
            return np.sort(w)
        return np.sort(self.omega)


def _initial(x0, v0) -> tuple[np.ndarray, np.ndarray]:
    x0 = np.asarray(x0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    if x0.shape != v0.shape or x0.ndim not in (1, 2) or x0.shape[0] < 1:
        raise ValueError(f"x0 and v0 must have the same shape (n,) or (n, B) with n >= 1; got {x0.shape}, "
                         f"{v0.shape}")
    return x0, v0


__all__ = ["ChainModal", "Basis", "MAX_FALLBACK"]
