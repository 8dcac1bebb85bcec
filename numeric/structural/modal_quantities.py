"""The modal quantities response-spectrum analysis prints, in extended precision, rounded once.

Float64 shapes, even correctly rounded ones, lose what RSA prints at high stiffness contrast: a
stiff spring's extension φ_b − φ_a is a difference of nearly equal components (k·ε·|φ| of error
on a force of the order of the soft springs'), and the participation Γⱼ = Σ mᵢφᵢⱼ of a mode
nearly orthogonal to r = 1 is a sum of terms of both signs. Here, for scenes of at most
:data:`MP_MAX_MASSES` masses:

1. ``D = M^-1/2 K M^-1/2`` is assembled exactly from the elements (every float parameter an exact
   binary fraction, :func:`numeric.frf.dense.to_mp`) and diagonalised by ``mpmath.eigsy`` at
   d₀ = 30 + log10(λ_max/λ_min) digits (the spread from the float64 spectrum), then 2d₀, 4d₀;
2. per mode (ascending ω, M-orthonormal physical shape φⱼ, the sign of its first non-negligible
   component positive, as the float route): Γⱼ, the peak quantities per unit spectral
   displacement Γⱼφⱼ (floors), Γⱼ(φ_b − φ_a) (drifts), k·Γⱼ(φ_b − φ_a) (spring forces),
   λⱼΓⱼ² = rᵀKΓⱼφⱼ (base shear), and G = ΦᵀCΦ (dashpots from their elements; Rayleigh
   α + βλⱼ and modal damping 2ζⱼωⱼ on the diagonal by definition) for ζⱼ = Gⱼⱼ/(2ωⱼ);
3. the precision doubles until two successive precisions agree on every one of these to
   :data:`SETTLED` relative once their difference is scaled to the higher precision (or to
   :data:`FLOOR` of the largest of its kind where a value is tiny: a high mode localised away from
   the wall can have Γ ~ 1e-60), and each is rounded to float64 once.

Cost (one core, measured): ``eigsy`` is about 1.2 s per precision at 24 masses (0.15 s at 12), so
:data:`MP_MAX_MASSES` is 24; two precisions settle a scene unless it has repeated frequencies.

Repeated frequencies (no unique shapes, so no unique per-mode values) do not settle: the caller
falls back to the float route and says so.
"""

from __future__ import annotations

import math

import numpy as np

from ..io.array_record import array_record
from ..modes.elements import Elements
from ..frf.dense import to_mp, mp_modes

#: Largest scene whose modal quantities are computed in mpmath (the cost grows with the digits the scene's contrast needs).
MP_MAX_MASSES = 24
#: Two successive precisions agreeing to this relative difference settle a value.
SETTLED = 1e-17
#: Values smaller than this fraction of the largest of their kind (over all modes) settle absolutely.
FLOOR = 1e-40
#: Margin on the error estimate of the higher precision (its difference from the lower one, scaled by
#: the ratio of their unit roundoffs).
SAFETY = 1e6
#: Digits of the first precision beyond log10 of the spread λ_max/λ_min; then doubled, :data:`LEVELS` in all.
DIGITS = 30
LEVELS = 3


@array_record
class ExactModes:
    """Per-mode quantities of the elastic modes, each correctly rounded from extended precision.

    Attributes
    ----------
    omega, gamma, zeta, base : ndarray, shape (J,)
        ω, Γ = φᵀM1, ζ = (ΦᵀCΦ)ⱼⱼ/(2ω), base shear per unit SD λΓ².
    shapes : ndarray, shape (N, J)
        M-orthonormal physical shapes.
    displacement : ndarray, shape (J, N)
        Γⱼφⱼ (floor displacement per unit SD).
    drift, force : ndarray, shape (J, S)
        Γⱼ(φ_b − φ_a) and k·Γⱼ(φ_b − φ_a) per unit SD.
    proportional : bool
        Whether ΦᵀCΦ is diagonal (to 1e-10 of its diagonal).
    digits : int
        The precision that settled.
    """

    omega: np.ndarray
    gamma: np.ndarray
    zeta: np.ndarray
    base: np.ndarray
    shapes: np.ndarray
    displacement: np.ndarray
    drift: np.ndarray
    force: np.ndarray
    proportional: bool = True
    digits: int = 0


def _at(el: Elements, dps: int) -> dict:
    """Every quantity of :class:`ExactModes` as mpmath numbers at ``dps`` digits (lists per mode)."""
    import mpmath

    with mpmath.workdps(dps):
        mp = lambda v: to_mp(v, mpmath)
        m = [mp(v) for v in el.masses.tolist()]
        springs = [(a, b, mp(k)) for (a, b), k in zip(el.spring_ends.tolist(), el.stiffness.tolist())]
        lam, shapes = mp_modes(el, mpmath)
        phi = []
        for col in shapes:
            big = max(abs(c) for c in col)
            first = next(c for c in col if abs(c) > mpmath.mpf("1e-12") * big)
            phi.append([-c for c in col] if first < 0 else col)
        x = lambda row, i: row[i] if i >= 0 else 0  # a wall does not move
        gamma = [mpmath.fsum(mi * c for mi, c in zip(m, row)) for row in phi]
        disp = [[g * c for c in row] for g, row in zip(gamma, phi)]
        drift = [[g * (x(row, b) - x(row, a)) for a, b, _ in springs] for g, row in zip(gamma, phi)]
        force = [[k * d for (_, _, k), d in zip(springs, row)] for row in drift]
        base = [lj * g * g for lj, g in zip(lam, gamma)]
        omega = [mpmath.sqrt(max(lj, 0)) for lj in lam]
        J = len(phi)
        G = [[mpmath.mpf(0)] * J for _ in range(J)]
        for (a, b), c in zip(el.damper_ends.tolist(), el.damping.tolist()):
            c = mp(c)
            ext = [x(row, a) - x(row, b) for row in phi]
            for i in range(J):
                for j in range(J):
                    G[i][j] += c * ext[i] * ext[j]
        diag = [G[j][j] for j in range(J)]
        if el.rayleigh is not None:
            al, be = (mp(v) for v in el.rayleigh)
            diag = [d + al + be * lj for d, lj in zip(diag, lam)]
        if el.modal_zeta is not None:
            diag = [d + 2 * mp(z) * w for d, z, w in zip(diag, el.modal_zeta.tolist(), omega)]
        zeta = [d / (2 * w) for d, w in zip(diag, omega)]
        off = max((abs(G[i][j]) for i in range(J) for j in range(J) if i != j), default=mpmath.mpf(0))
        proportional = bool(off <= mpmath.mpf("1e-10") * max(max(abs(d) for d in diag), mpmath.mpf("1e-300")))
        return {"omega": omega, "gamma": gamma, "zeta": zeta, "base": base, "shapes": phi,
                "displacement": disp, "drift": drift, "force": force, "proportional": proportional}


_PER_MODE = ("omega", "gamma", "zeta", "base")
_ROWS = ("shapes", "displacement", "drift", "force")


def _settled(a: dict, b: dict, gain: float) -> bool:
    """Whether every value of ``b`` is settled: its estimated error, the difference from ``a`` (computed
    with ``gain`` times the unit roundoff of ``b``) times ``gain`` times :data:`SAFETY`, is at most
    :data:`SETTLED` of it or :data:`FLOOR` of the largest value of its kind (over all modes)."""
    for key in _PER_MODE + _ROWS:
        flat_a = [v for row in a[key] for v in row] if key in _ROWS else a[key]
        flat_b = [v for row in b[key] for v in row] if key in _ROWS else b[key]
        scale = max((abs(v) for v in flat_b), default=0)
        if not all(abs(u - v) * gain * SAFETY <= SETTLED * abs(v) + FLOOR * scale for u, v in zip(flat_a, flat_b)):
            return False
    return True


def exact_modes(el: Elements, omega: np.ndarray) -> ExactModes | None:
    """The modal quantities of an all-elastic scene (every piece tied to a wall) settled in mpmath;
    None where they do not settle within :data:`LEVELS` precisions (repeated frequencies).

    Parameters
    ----------
    el : Elements
    omega : ndarray, shape (N,)
        The float64 frequencies (accurate spectrum), for the first precision.
    """
    import mpmath

    spread = float(np.max(omega) / np.min(omega)) ** 2 if np.min(omega) > 0 else 1e300
    first = DIGITS + math.ceil(math.log10(max(spread, 1.0)))
    prev = None
    for dps in (first << i for i in range(LEVELS)):
        cur = _at(el, dps)
        if prev is not None:
            with mpmath.workdps(dps):
                ok = _settled(prev, cur, mpmath.mpf(10) ** -(dps // 2))
            if ok:
                f = lambda v: np.array([float(u) for u in v])  # the one rounding
                rows = {key: np.array([[float(u) for u in row] for row in cur[key]]).reshape(len(cur["omega"]), -1)
                        for key in _ROWS}
                return ExactModes(*(f(cur[key]) for key in _PER_MODE), rows["shapes"].T, rows["displacement"],
                                  rows["drift"], rows["force"], cur["proportional"], dps)
        prev = cur
    return None


__all__ = ["ExactModes", "exact_modes", "MP_MAX_MASSES"]


def _signed_spectrum(system):
    """``(elements, spectrum, shapes)`` of a chain: the accurate spectrum (:func:`numeric.modes.spectrum.spectrum`)
    and its mass-normalised shapes as columns, each signed so that its first non-negligible component is
    positive."""
    from ..modes.spectrum import spectrum

    el = Elements.from_system(system)
    spec = spectrum(el.masses, el.spring_ends, el.stiffness)
    phi = spec.shapes
    first = np.argmax(np.abs(phi) > 1e-12 * np.max(np.abs(phi), axis=0, keepdims=True), axis=0)
    phi = phi * np.where(phi[first, np.arange(phi.shape[1])] < 0, -1.0, 1.0)[None, :]
    return el, spec, phi


def chain_mode_shapes(system) -> tuple[np.ndarray, np.ndarray]:
    """``(ω², shapes)`` of a chain (open or ring) without closed-form modes, from the accurate spectrum:
    shapes (n, n) one row per mode in ascending ω², mass-normalised (φᵀMφ = 1), the first non-negligible
    component of each positive (as :func:`chain_participation`); inside a repeated ω² an orthonormal basis."""
    _, spec, phi = _signed_spectrum(system)
    return spec.omega2, phi.T


def chain_participation(system) -> tuple[np.ndarray, list[float], np.ndarray, float]:
    """``(ω², Γ, shapes, total mass)`` of an open chain (a :class:`~springchain.numeric.system.System`) from the
    spring-factor SVD: shapes mass-normalised, shape (n, n) one row per mode, each signed so that its first
    non-negligible component is positive (as ``rsa``); Γⱼ = Σ mᵢφᵢⱼ by compensated sums, and for a free–free
    chain Γ = (√M, 0, …, 0) exactly by structure (r = 1 is its rigid mode)."""
    el, spec, phi = _signed_spectrum(system)
    m = np.asarray(el.masses, dtype=float)
    total = math.fsum(m)
    if spec.rigid:
        gamma = [math.sqrt(total)] + [0.0] * (phi.shape[1] - 1)
    else:
        gamma = [math.fsum(m * phi[:, j]) for j in range(phi.shape[1])]
    return spec.omega2, gamma, phi.T, total
