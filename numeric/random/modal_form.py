"""A linear scene's responses in pole–residue form, ``H_y(s) = D_y + Σ_r R_yr / (s − λ_r)``.

Built in the accurate undamped modal basis (ω and M-orthonormal Φ of the spring-factor SVD,
:mod:`numeric.modes.spectrum`; ``G = ΦᵀCΦ`` from the elements, :func:`numeric.modes.elements.modal_damping`):

* **proportional damping** (G diagonal by construction: Rayleigh, modal): each mode's two poles
  in closed form, ``λ = −g/2 ± i√((ω − g/2)(ω + g/2))`` (overdamped: ``λ₁ = −(g + √(g² − 4ω²))/2``,
  ``λ₂ = ω²/λ₁``, no cancellation), and its residues ``±p/(λ₁ − λ₂)``;
* **dashpots** (G full): the eigen-decomposition of the balanced first-order modal matrix
  ``[[0, Ω], [−Ω, −G]]`` (every block of size ω), residues ``V (V⁻¹ b)``; refused in one line when
  its eigenvectors are too ill-conditioned (near-critical damping).

Velocity and acceleration residues are ``λ R`` and ``λ² R`` with direct terms 0 and ``M⁻¹b``
(exact, not summed). For base acceleration the accelerations are absolute (direct term 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..modes.elements import Elements, incidence, modal_damping
from ..errors import RunRefused
from ..modes.spectrum import spectrum

#: Largest scene whose random response is computed (the modal basis is dense N × N).
MAX_MASSES = 400
#: Poles closer than this (relative) make a mode critically damped: refused.
CRITICAL_GAP = 1e-7
#: Largest condition number of the first-order eigenvectors accepted (dashpots).
MAX_CONDITION = 1e8


@dataclass(frozen=True)
class PoleResidue:
    """Outputs ``y`` of a linear scene driven by one input, in pole–residue form.

    Attributes
    ----------
    poles : ndarray, shape (P,), complex
        All with Re λ < 0.
    residues : ndarray, shape (Y, P), complex
    direct : ndarray, shape (Y,)
        Feedthrough ``D_y``.
    names, kinds, units : tuple of str, length Y
        ``"m1"``/``"spring 0 (m1-wall)"``; ``"displacement"``, ``"velocity"``, ``"acceleration"``,
        ``"spring force"``; SI units per unit input.
    omega_n, zeta : ndarray, shape (M,)
        The undamped ω of the modes and the damping ratios ``g/(2ω)`` (diagonal of G).
    """

    poles: np.ndarray = field(repr=False)
    residues: np.ndarray = field(repr=False)
    direct: np.ndarray = field(repr=False)
    names: tuple = ()
    kinds: tuple = ()
    units: tuple = ()
    omega_n: np.ndarray = field(default=None, repr=False)
    zeta: np.ndarray = field(default=None, repr=False)

    def response(self, omega: np.ndarray) -> np.ndarray:
        """``H_y(iω)``, shape (Y, W), complex."""
        omega = np.asarray(omega, dtype=float).reshape(-1)
        inv = 1.0 / (1j * omega[None, :] - self.poles[:, None])
        return self.direct[:, None] + self.residues @ inv


def _proportional(w: np.ndarray, g: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poles (2M,) and modal displacement residues (M, 2M) of decoupled modes q̈ + g q̇ + ω² q = p u."""
    m = w.shape[0]
    half = 0.5 * g
    under = half < w
    root = np.sqrt(np.abs((w - half) * (w + half)))
    l1 = np.where(under, -half + 1j * root, -(half + root) + 0j)
    l2 = np.where(under, -half - 1j * root, (w * w) / np.where(under, 1.0, -(half + root)) + 0j)
    gap = np.abs(l1 - l2)
    bad = gap <= CRITICAL_GAP * np.abs(l1)
    if bad.any():
        j = int(np.argmax(bad))
        raise RunRefused(f"random response: mode {j + 1} (omega = {w[j]:.6g} rad/s) is critically damped "
                         f"(zeta = {g[j] / (2 * w[j]):.9g}): its two poles coincide; accepted: zeta away from 1",
                         quantity="scene")
    rho = p / (l1 - l2)
    poles = np.concatenate([l1, l2])
    R = np.zeros((m, 2 * m), dtype=complex)
    R[np.arange(m), np.arange(m)] = rho
    R[np.arange(m), m + np.arange(m)] = -rho
    return poles, R


def _coupled(w: np.ndarray, G: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poles (2M,) and modal displacement residues (M, 2M) of q̈ + G q̇ + Ω² q = p u (G full)."""
    m = w.shape[0]
    A = np.zeros((2 * m, 2 * m))
    A[np.arange(m), m + np.arange(m)] = w
    A[m + np.arange(m), np.arange(m)] = -w
    A[m:, m:] = -G
    lam, V = scipy.linalg.eig(A)
    cond = np.linalg.cond(V)
    if not cond <= MAX_CONDITION:
        raise RunRefused(f"random response: the damped modes are nearly defective (eigenvector condition "
                         f"{cond:.2g}, near-critical damping); accepted: dashpots that leave the modes distinct",
                         quantity="scene")
    b = np.concatenate([np.zeros(m), p]).astype(complex)
    beta = np.linalg.solve(V, b)
    R = (V[:m] * beta[None, :]) / w[:, None]  # q = Ω⁻¹ (ω q)
    return lam, R


def pole_residue(el: Elements, b: np.ndarray, *, ground: bool, names: tuple[str, ...]) -> PoleResidue:
    """Every mass's displacement, velocity, acceleration and every spring's force per unit input.

    Parameters
    ----------
    el : Elements
        The linear scene (springs by their linear stiffness).
    b : ndarray, shape (N,)
        Force per unit input on each mass: ``e_k`` for a force on mass k, ``−m`` for a base
        acceleration (relative coordinates).
    ground : bool
        Base acceleration: accelerations absolute.
    names : tuple of str, length N
        Mass names.

    Raises
    ------
    RunRefused
        More than :data:`MAX_MASSES` masses, a rigid-body mode, an undamped mode, a critically
        damped one.
    """
    n = el.n
    if n > MAX_MASSES:
        raise RunRefused(f"random response of {n} masses: at most {MAX_MASSES} (the modal basis is dense)",
                         quantity="scene")
    spec = spectrum(el.masses, el.spring_ends, el.stiffness)
    if spec.rigid:
        raise RunRefused(f"random response: the scene has {spec.rigid} free piece(s) (rigid-body modes): a free "
                         "body's displacement has no stationary RMS; accepted: every mass held by springs to a wall",
                         quantity="scene")
    w, Phi = spec.omega, spec.shapes
    G = modal_damping(el, w, Phi)
    g = np.diag(G).copy()
    undamped = g <= 0
    if el.proportional and undamped.any():
        j = int(np.argmax(undamped))
        raise RunRefused(f"random response: mode {j + 1} (omega = {w[j]:.6g} rad/s) is undamped: its response to "
                         "a random input is unbounded; accepted: a scene whose every mode is damped", quantity="scene")
    p = Phi.T @ b
    poles, Rq = _proportional(w, g, p) if el.proportional else _coupled(w, G, p)
    if not np.all(poles.real < -1e-12 * np.abs(poles)):
        raise RunRefused("random response: a mode is undamped (a pole on the imaginary axis): its response to a "
                         "random input is unbounded; accepted: a scene whose every mode is damped", quantity="scene")
    x = Phi @ Rq
    v = x * poles[None, :]
    a = x * (poles * poles)[None, :]
    direct_a = np.zeros(n) if ground else b / el.masses
    B = incidence(n, el.spring_ends)
    springs = (el.stiffness[:, None] * B) @ x
    label = lambda j: names[j] if j >= 0 else "wall"  # noqa: E731
    spring_names = tuple(f"spring {e} ({label(a_)}-{label(b_)})" for e, (a_, b_) in enumerate(el.spring_ends.tolist()))
    unit_in = "m/s^2" if ground else "N"
    per = lambda u: f"({u})/({unit_in})"  # noqa: E731
    kinds = ("displacement",) * n + ("velocity",) * n + ("acceleration",) * n + ("spring force",) * len(spring_names)
    units = ((per("m"),) * n + (per("m/s"),) * n + (per("m/s^2"),) * n + (per("N"),) * len(spring_names))
    return PoleResidue(poles, np.vstack([x, v, a, springs]),
                       np.concatenate([np.zeros(2 * n), direct_a, np.zeros(len(spring_names))]),
                       tuple(names) * 3 + spring_names, kinds, units, w, g / (2 * w))


__all__ = ["PoleResidue", "pole_residue", "MAX_MASSES"]
