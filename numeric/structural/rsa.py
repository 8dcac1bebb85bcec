"""Response-spectrum analysis: peak modal responses of a building to a spectrum, combined by SRSS or CQC.

Each elastic mode j (M-orthonormal shape φⱼ from the accurate spring-factor route, ω_j, damping
ratio ζⱼ = φⱼᵀCφⱼ/(2ωⱼ)) responds to the ground like a single oscillator scaled by its
participation factor Γⱼ = φⱼᵀM1: the peak modal displacement vector is uⱼ = Γⱼ φⱼ SDⱼ with
SDⱼ = SD(Tⱼ, ζⱼ) of a record's spectrum (exact, :mod:`numeric.structural.response_spectrum`) or
Sa(Tⱼ)/ωⱼ² of a design spectrum. From uⱼ, per spring s between ends a → b: the drift
(inter-storey drift) x_b − x_a, the spring force k_s(x_b − x_a) (the storey shear of a shear
building) and the base shear, the force the wall springs put on the ground,
Vⱼ = rᵀK uⱼ = Mⱼ*·PSAⱼ.

Combination of the modal peaks R_j of any of these quantities:

* SRSS: R = √(Σⱼ Rⱼ²);
* CQC (Der Kiureghian, 1981): R = √(Σᵢ Σⱼ ρᵢⱼ Rᵢ Rⱼ) with
  ρᵢⱼ = 8√(ζᵢζⱼ)(ζᵢ + rζⱼ) r^{3/2} / ((1 − r²)² + 4ζᵢζⱼ r(1 + r²) + 4(ζᵢ² + ζⱼ²) r²),
  r = ωⱼ/ωᵢ (ρᵢᵢ = 1). Its denominator is a sum of non-negative terms, positive for ζ > 0:
  nothing divides by a frequency difference; for well-separated modes ρ → 0 and CQC → SRSS.
"""

from __future__ import annotations

import enum
import math
from dataclasses import field

import numpy as np

from ..io.array_record import array_record
from ..modes.elements import Elements
from ..errors import RunRefused
from .modal_quantities import MP_MAX_MASSES, ExactModes, exact_modes
from ..system import System


class Combination(enum.Enum):
    """How peak modal responses are combined."""

    SRSS = "srss"
    CQC = "cqc"


def cqc_correlation(omega: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Der Kiureghian's modal correlation coefficients ρᵢⱼ, shape (J, J), ρᵢᵢ = 1.

    Parameters
    ----------
    omega : ndarray, shape (J,)
        Natural frequencies (> 0).
    zeta : ndarray, shape (J,)
        Damping ratios (>= 0; two undamped distinct modes are uncorrelated).
    """
    w = np.asarray(omega, dtype=float)
    z = np.asarray(zeta, dtype=float)
    r = w[None, :] / w[:, None]
    one_minus_r2 = (w[:, None] - w[None, :]) * (w[:, None] + w[None, :]) / w[:, None] ** 2  # 1 − r², no cancellation
    zi, zj = z[:, None], z[None, :]
    num = 8.0 * np.sqrt(zi * zj) * (zi + r * zj) * r**1.5
    den = one_minus_r2**2 + 4.0 * zi * zj * r * (1.0 + r**2) + 4.0 * (zi**2 + zj**2) * r**2
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    np.fill_diagonal(rho, 1.0)
    return rho


def combine(peaks: np.ndarray, how: Combination, rho: np.ndarray | None = None) -> np.ndarray:
    """Combine modal peaks ``peaks`` (shape (J, ...)) by SRSS or CQC (``rho`` of :func:`cqc_correlation`)."""
    R = np.asarray(peaks, dtype=float)
    if how is Combination.SRSS:
        return np.sqrt(np.sum(R**2, axis=0))
    flat = R.reshape(R.shape[0], -1)
    quad = np.einsum("i...,ij,j...->...", flat, rho, flat)
    return np.sqrt(np.maximum(quad, 0.0)).reshape(R.shape[1:])


@array_record
class ModalProperties:
    """The elastic modes of a system as RSA needs them.

    Attributes
    ----------
    omega, zeta, gamma : ndarray, shape (J,)
    shapes : ndarray, shape (N, J)
        M-orthonormal physical shapes.
    effective_mass : ndarray, shape (J,)
    total_mass : float
    proportional : bool
        Whether ΦᵀCΦ is diagonal (to 1e-10 of its diagonal); otherwise ζ is its diagonal, an approximation.
    exact : ExactModes or None
        The per-unit-SD peaks of every mode, each correctly rounded (:mod:`numeric.structural.modal_quantities`);
        None on the float route (more than ``MP_MAX_MASSES`` masses, or repeated frequencies).
    """

    omega: np.ndarray
    zeta: np.ndarray
    gamma: np.ndarray
    shapes: np.ndarray
    total_mass: float = 0.0
    proportional: bool = True
    exact: ExactModes | None = field(default=None, repr=False)

    @property
    def effective_mass(self) -> np.ndarray:
        return self.gamma**2

    @property
    def periods(self) -> np.ndarray:
        return 2.0 * np.pi / self.omega

    @classmethod
    def from_system(cls, system: System) -> "ModalProperties":
        """Modes by the spring-factor SVD (rigid modes refused); Γ, ζ and the per-unit-SD peaks from
        :func:`numeric.structural.modal_quantities.exact_modes` up to ``MP_MAX_MASSES`` masses, else ζ from the
        system's damping matrix and Γ by compensated sums of the float64 shapes."""
        from ..modes.spectrum import spectrum

        if system.chain and system.n > 2000:
            raise RunRefused(f"response-spectrum analysis of a [chain] of {system.n} masses: the modes are dense; "
                             "accepted: at most 2000 masses", quantity="scene")
        spec = spectrum(system.masses, system.spring_ends, system.stiffness)
        if spec.rigid:
            raise RunRefused(f"response-spectrum analysis needs every mass tied to a wall: this scene has "
                             f"{spec.rigid} free piece(s) (rigid-body modes, infinite period); accepted: a scene "
                             "whose every piece has a spring to a wall", quantity="scene")
        if system.n <= MP_MAX_MASSES:
            from ..progress import phase

            with phase(f"modal quantities of {system.n} masses in extended precision"):
                ex = exact_modes(Elements.from_system(system), spec.omega)
            if ex is not None:
                return cls(ex.omega, ex.zeta, ex.gamma, ex.shapes, float(math.fsum(system.masses)),
                           ex.proportional, ex)
        phi = spec.shapes
        # the sign of each shape: its first non-zero component positive (as the printed closed-form shapes)
        first = np.argmax(np.abs(phi) > 1e-12 * np.max(np.abs(phi), axis=0, keepdims=True), axis=0)
        phi = phi * np.where(phi[first, np.arange(phi.shape[1])] < 0, -1.0, 1.0)[None, :]
        m = system.masses
        gamma = np.array([math.fsum(m * phi[:, j]) for j in range(phi.shape[1])])
        omega = spec.omega
        zeta = np.zeros_like(omega)
        proportional = True
        if system.damped:
            if system.chain:
                C = -system.damping_rate_matrix() * m[:, None]
                C = C.toarray() if hasattr(C, "toarray") else np.asarray(C)
            else:
                C = system.damping_matrix()
            G = phi.T @ C @ phi
            d = np.diag(G)
            off = G - np.diag(d)
            proportional = bool(np.max(np.abs(off), initial=0.0) <= 1e-10 * max(float(np.max(np.abs(d))), 1e-300))
            zeta = d / (2.0 * omega)
        return cls(omega, zeta, gamma, phi, float(math.fsum(m)), proportional)


@array_record
class RSAResult:
    """Peak modal responses and their SRSS and CQC combinations.

    Attributes
    ----------
    modes : ModalProperties
    sd : ndarray, shape (J,)
        Spectral displacement of each mode [m].
    displacement : ndarray, shape (J, N)
        Peak modal floor displacements Γⱼ φⱼ SDⱼ (signed) [m].
    drift : ndarray, shape (J, S)
        Peak modal drifts x_b − x_a of each spring [m].
    spring_force : ndarray, shape (J, S)
        Peak modal spring forces (storey shears) [N].
    base_shear : ndarray, shape (J,)
        Peak modal base shear Mⱼ*·PSAⱼ [N].
    rho : ndarray, shape (J, J)
        CQC correlation coefficients.
    spectrum : str
        What the spectrum was (a record's name or a design spectrum's file).
    """

    modes: ModalProperties
    sd: np.ndarray
    displacement: np.ndarray
    drift: np.ndarray
    spring_force: np.ndarray
    base_shear: np.ndarray
    rho: np.ndarray
    spectrum: str = ""

    @property
    def psa(self) -> np.ndarray:
        return self.sd * self.modes.omega**2

    def combined(self, how: Combination) -> dict[str, np.ndarray]:
        """``displacement`` (N,), ``drift`` (S,), ``spring_force`` (S,), ``base_shear`` () combined."""
        rho = self.rho if how is Combination.CQC else None
        return {"displacement": combine(self.displacement, how, rho), "drift": combine(self.drift, how, rho),
                "spring_force": combine(self.spring_force, how, rho),
                "base_shear": float(combine(self.base_shear, how, rho))}

    def to_json(self) -> dict:
        m = self.modes
        modal = [{"mode": j + 1, "period": float(m.periods[j]), "omega": float(m.omega[j]),
                  "zeta": float(m.zeta[j]), "participation_factor": float(m.gamma[j]),
                  "effective_mass": float(m.effective_mass[j]), "sd": float(self.sd[j]), "psa": float(self.psa[j]),
                  "displacement": self.displacement[j].tolist(), "drift": self.drift[j].tolist(),
                  "spring_force": self.spring_force[j].tolist(), "base_shear": float(self.base_shear[j])}
                 for j in range(m.omega.shape[0])]
        out = {"spectrum": self.spectrum, "total_mass": m.total_mass, "proportional_damping": m.proportional,
               "modes": modal, "cqc_correlation": self.rho.tolist()}
        for how in Combination:
            out[how.value] = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                              for k, v in self.combined(how).items()}
        return out


def spring_geometry(system: System) -> tuple[np.ndarray, np.ndarray]:
    """Incidence of drifts ``x_b − x_a`` (S, N) as a dense matrix, and the base-shear sign of each spring (S,)."""
    ends = system.spring_ends
    S, N = ends.shape[0], system.n
    B = np.zeros((S, N))
    rows = np.arange(S)
    a, b = ends[:, 0], ends[:, 1]
    B[rows[b >= 0], b[b >= 0]] += 1.0
    B[rows[a >= 0], a[a >= 0]] -= 1.0
    sign = np.where(a < 0, 1.0, 0.0) - np.where(b < 0, 1.0, 0.0)
    return B, sign


def analyse(system: System, sd: np.ndarray, modes: ModalProperties, spectrum: str = "") -> RSAResult:
    """Peak modal responses for the spectral displacements ``sd`` (shape (J,)) of the system's modes."""
    sd = np.asarray(sd, dtype=float)
    if modes.exact is not None:  # each per-unit peak correctly rounded: one more rounding here
        ex = modes.exact
        u, drift, force, base = (ex.displacement * sd[:, None], ex.drift * sd[:, None], ex.force * sd[:, None],
                                 ex.base * sd)
    else:
        u, drift, force, base = _float_peaks(system, modes, sd)
    return RSAResult(modes, sd, u, drift, force, base, cqc_correlation(modes.omega, modes.zeta), spectrum)


def _float_peaks(system: System, modes: ModalProperties, sd: np.ndarray) -> tuple:
    """Peaks from float64 shapes (the route past ``MP_MAX_MASSES`` masses): floors Γφ·SD, base shear
    λΓ²·SD (= rᵀK u, no sum of signed forces). Spring forces of a chain hanging from one wall are storey
    shears, λ Σ_{masses beyond} mᵢφᵢ (the inertia forces beyond the spring: a stiff spring's force is
    never a difference of nearly equal displacements times k); other topologies take k(x_b − x_a)."""
    g = modes.gamma * sd
    u = g[:, None] * modes.shapes.T  # (J, N)
    B, _ = spring_geometry(system)
    drift = u @ B.T
    force = drift * system.stiffness[None, :]
    lam = modes.omega**2
    ends, n = system.spring_ends, system.n
    path = np.stack([np.arange(-1, n - 1), np.arange(n)], axis=1)
    inertia = lam[:, None] * (system.masses[None, :] * u)  # (J, N)
    if ends.shape == path.shape and np.array_equal(ends, path):  # wall - 0 - 1 - ... - n-1 (free)
        force = np.cumsum(inertia[:, ::-1], axis=1)[:, ::-1]
        drift = force / system.stiffness[None, :]
    elif ends.shape == path.shape and np.array_equal(ends, np.stack([np.arange(n), np.r_[np.arange(1, n), -1]], 1)):
        force = -np.cumsum(inertia, axis=1)  # 0 - 1 - ... - n-1 - wall: f_s = -λ Σ_{i<=s} m_i φ_i
        drift = force / system.stiffness[None, :]
    return u, drift, force, lam * modes.gamma**2 * sd


__all__ = ["Combination", "cqc_correlation", "combine", "ModalProperties", "RSAResult", "analyse",
           "spring_geometry"]
