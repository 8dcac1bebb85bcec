"""The energy in each linear normal mode about the equilibrium, frame by frame.

For a state (x, v) and the M-orthonormal modes Φ of K = Hessian of V at x_eq (ascending ω, rigid
modes first, exact zeros by structure), the modal coordinates are ``q = Φᵀ M (x − x_eq)`` and
``q̇ = Φᵀ M v``, and the harmonic energy of mode j is

    E_j = ½ (q̇_j² + ω_j² q_j²).

For a linear scene Σ_j E_j is the energy (and each E_j is conserved); for a nonlinear one (FPUT,
Toda) the E_j show how energy moves between modes — the Fermi–Pasta–Ulam–Tsingou recurrence.

Two routes, one answer:

* **Uniform chains** (every mass m, every spring the same): the modes are sines, cosines or
  Fourier modes, so q is one fast transform of √m·(x − x_eq) (:mod:`numeric.exact.chain`'s DCT-II,
  DST-I, odd DST-I, real FFT), O(N log N) per frame and no N × N matrix; ω from the module's
  closed-form ``mode_omega()``.
* **Anything else** up to :data:`MAX_DENSE_MODES` masses: the accurate spectrum
  (:func:`numeric.modes.spectrum.spectrum`, the spring-factor SVD), q = Eᵀ √m (x − x_eq), O(N²) per frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...generated.contract import MAX_DENSE, End
from .chain import Basis, basis_of, forward_transform
from ..errors import RunRefused
from ..system import System

#: Largest non-uniform scene whose modal energies are computed through dense eigenvectors.
MAX_DENSE_MODES = MAX_DENSE


@dataclass(frozen=True)
class ModalEnergy:
    """Projection of states onto the linear normal modes about ``x_eq``.

    Attributes
    ----------
    omega : ndarray, shape (N,)
        Angular frequencies, ascending (the order of the energies returned).
    x_eq : ndarray, shape (N,)
        The static equilibrium.
    basis : Basis
        The fast transform of a uniform chain, or ``Basis.EIGENVECTORS``.
    """

    omega: np.ndarray = field(repr=False)
    x_eq: np.ndarray = field(repr=False)
    basis: Basis
    sqrt_mass: np.ndarray = field(repr=False)
    order: np.ndarray = field(repr=False)
    vectors: np.ndarray | None = field(default=None, repr=False)
    reverse: bool = False

    @classmethod
    def from_system(cls, system: System) -> "ModalEnergy":
        """The modes of a scene's generated module at its parameter values (linearised about x_eq)."""
        n = system.n
        x_eq = _equilibrium(system)
        sqrt_m = np.sqrt(system.masses)
        if system.chain and system.uniform and system.has("mode_omega"):
            left, right = system.ends
            basis = basis_of(left, right)
            omega_index = system.mode_omega()
            if basis is Basis.FFT:  # real coefficients: cos_j (j = 0 … n/2) then sin_j (0 < j < n/2)
                j = np.arange(n // 2 + 1)
                sin_j = np.arange(1, (n + 1) // 2)
                omega_index = np.concatenate([omega_index[j], omega_index[sin_j]])
            order = np.argsort(omega_index, kind="stable")
            return cls(omega_index[order], x_eq, basis, sqrt_m, order,
                       reverse=left is End.FREE and right is End.WALL)
        if n > MAX_DENSE_MODES:
            raise RunRefused(f"modal energies of a non-uniform scene of {n} masses need its eigenvectors "
                             f"(dense, limited to {MAX_DENSE_MODES} masses); accepted: a uniform chain "
                             "(fast transforms) or a smaller scene", quantity="modal_energy")
        from ..modes.spectrum import spectrum

        spec = spectrum(system.masses, system.spring_ends, system.stiffness)
        return cls(spec.omega, x_eq, Basis.EIGENVECTORS, sqrt_m, np.arange(n), spec.vectors)

    def coordinates(self, y: np.ndarray) -> np.ndarray:
        """Modal coordinates of mass-weighted y = √m·u (axis 0 = masses), in ascending ω order."""
        if self.basis is Basis.EIGENVECTORS:
            return np.tensordot(self.vectors.T, y, axes=1)
        if self.reverse:
            y = y[::-1]
        c = forward_transform(self.basis, y)
        if self.basis is Basis.FFT:
            n = y.shape[0]
            scale = np.full(n // 2 + 1, np.sqrt(2.0 / n))
            scale[0] = 1.0 / np.sqrt(n)
            if n % 2 == 0:
                scale[-1] = 1.0 / np.sqrt(n)
            shape = (-1,) + (1,) * (y.ndim - 1)
            cos_part = c.real * scale.reshape(shape)
            sin_part = -c.imag[1:(n + 1) // 2] * np.sqrt(2.0 / n)
            c = np.concatenate([cos_part, sin_part])
        return c[self.order]

    def energies(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """E_j of states: x, v shape (N,) -> (N,), or frames (S, N) -> (S, N), ascending ω."""
        x = np.asarray(x, dtype=float)
        v = np.asarray(v, dtype=float)
        frames = x.ndim == 2
        xs, vs = (x.T, v.T) if frames else (x, v)
        shape = (-1,) + (1,) * (xs.ndim - 1)
        r = self.sqrt_mass.reshape(shape)
        q = self.coordinates(r * (xs - self.x_eq.reshape(shape)))
        p = self.coordinates(r * vs)
        e = 0.5 * (p * p + (self.omega.reshape(shape) * q) ** 2)
        return e.T if frames else e


def _equilibrium(system: System) -> np.ndarray:
    """x_eq: the module's ``equilibrium()`` (scenes with potentials), the cancellation-free sag of a linear
    scene under gravity (:func:`numeric.exact.equilibrium.equilibrium`), else 0."""
    n = system.n
    if system.potential:
        return system.potential_equilibrium()
    if "gravity" not in system.effects:
        return np.zeros(n)
    from .equilibrium import equilibrium

    eq = equilibrium(system.masses, system.spring_ends, system.stiffness, [system.gravity_forces()])
    if np.any(eq.acceleration != 0):
        raise RunRefused("modal energies about an equilibrium: a free piece under gravity has none (it "
                         "accelerates); accepted: scenes whose pieces under gravity hang from a wall",
                         quantity="modal_energy")
    return eq.x


def modal_energy_record(system: System, x: dict, v: dict) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """``modal_energy_<method>`` (S × N) of every run, for the NPZ, and the modes' ω (ascending)."""
    me = ModalEnergy.from_system(system)
    return {f"modal_energy_{m}": me.energies(x[m], v[m]) for m in x}, me.omega


def modal_energy_figure(out, scene_name: str, t: np.ndarray, energies: dict[str, np.ndarray], omega: np.ndarray):
    """``<scene>-modal-energy.png``: the lowest modes' energies over time (of the first method run)."""
    from pathlib import Path

    from ..plots import figures as plots

    key, e = next(iter(energies.items()))
    method = key[len("modal_energy_"):]
    fig = plots.modal_energies(t, e, omega, f"{scene_name}: energy of the lowest linear modes ({method})")
    path = Path(out) / f"{scene_name}-modal-energy.png"
    plots.save(fig, path)
    return path


__all__ = ["ModalEnergy", "modal_energy_record", "modal_energy_figure", "MAX_DENSE_MODES"]
