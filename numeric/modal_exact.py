"""The modal quantities response-spectrum analysis prints, in extended precision, rounded once.

Float64 shapes, even correctly rounded ones, lose what RSA prints at high stiffness contrast: a
stiff spring's extension φ_b − φ_a is a difference of nearly equal components (k·ε·|φ| of error
on a force of the order of the soft springs'), and the participation Γⱼ = Σ mᵢφᵢⱼ of a mode
nearly orthogonal to r = 1 is a sum of terms of both signs. Here, for scenes of at most
:data:`MP_MAX_MASSES` masses:

1. ``D = M^-1/2 K M^-1/2`` is assembled exactly from the elements (every float parameter an exact
   binary fraction, :func:`numeric.frf_dense._mp`) and diagonalised by ``mpmath.eigsy`` at 30, 60,
   120, … digits;
2. per mode (ascending ω, M-orthonormal physical shape φⱼ, the sign of its first non-negligible
   component positive, as the float route): Γⱼ, the peak quantities per unit spectral
   displacement Γⱼφⱼ (floors), Γⱼ(φ_b − φ_a) (drifts), k·Γⱼ(φ_b − φ_a) (spring forces),
   λⱼΓⱼ² = rᵀKΓⱼφⱼ (base shear), and G = ΦᵀCΦ (dashpots from their elements; Rayleigh
   α + βλⱼ and modal damping 2ζⱼωⱼ on the diagonal by definition) for ζⱼ = Gⱼⱼ/(2ωⱼ);
3. the precision doubles until two successive precisions agree on every one of these to
   :data:`SETTLED` relative (or :data:`FLOOR` of the mode's largest where a value is tiny), and
   each is rounded to float64 once.

Repeated frequencies (no unique shapes, so no unique per-mode values) do not settle: the caller
falls back to the float route and says so.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .elements import Elements
from .frf_dense import _mp

#: Largest scene whose modal quantities are computed in mpmath (cost measured in the README's rsa section).
MP_MAX_MASSES = 40
#: Two successive precisions agreeing to this relative difference settle a value.
SETTLED = 1e-17
#: Values smaller than this fraction of their mode's largest (of the same kind) settle absolutely.
FLOOR = 1e-15
#: Precisions tried (decimal digits).
DIGITS = (30, 60, 120, 240)


@dataclass(frozen=True)
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

    omega: np.ndarray = field(repr=False)
    gamma: np.ndarray = field(repr=False)
    zeta: np.ndarray = field(repr=False)
    base: np.ndarray = field(repr=False)
    shapes: np.ndarray = field(repr=False)
    displacement: np.ndarray = field(repr=False)
    drift: np.ndarray = field(repr=False)
    force: np.ndarray = field(repr=False)
    proportional: bool = True
    digits: int = 0


def _at(el: Elements, dps: int) -> dict:
    """Every quantity of :class:`ExactModes` as mpmath numbers at ``dps`` digits (lists per mode)."""
    import mpmath

    n = el.n
    with mpmath.workdps(dps):
        mp = lambda v: _mp(v, mpmath)  # noqa: E731
        m = [mp(v) for v in el.masses.tolist()]
        s = [1 / mpmath.sqrt(v) for v in m]
        springs = [(a, b, mp(k)) for (a, b), k in zip(el.spring_ends.tolist(), el.stiffness.tolist())]
        D = mpmath.zeros(n, n)
        for a, b, k in springs:  # the spring's stamp k·bbᵀ, scaled by M^-1/2 on both sides
            if a == b:
                continue
            for p, sp in ((a, 1), (b, -1)):
                for q, sq in ((a, 1), (b, -1)):
                    if p >= 0 and q >= 0:
                        D[p, q] += sp * sq * k * s[p] * s[q]
        lam, E = mpmath.eigsy(D)
        order = sorted(range(n), key=lambda j: lam[j])
        lam = [lam[j] for j in order]
        phi = []
        for j in order:
            col = [E[i, j] * s[i] for i in range(n)]
            big = max(abs(c) for c in col)
            first = next(c for c in col if abs(c) > mpmath.mpf("1e-12") * big)
            phi.append([-c for c in col] if first < 0 else col)
        x = lambda row, i: row[i] if i >= 0 else 0  # noqa: E731  (a wall does not move)
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


def _settled(a: dict, b: dict) -> bool:
    """Whether every value of ``b`` agrees with ``a`` (one precision lower) to :data:`SETTLED`."""
    def close(u, v, scale):
        return abs(u - v) <= SETTLED * abs(v) + FLOOR * SETTLED * scale

    for key in _PER_MODE:
        scale = max(abs(v) for v in b[key])
        if not all(close(u, v, scale) for u, v in zip(a[key], b[key])):
            return False
    for key in _ROWS:
        for ra, rb in zip(a[key], b[key]):
            scale = max((abs(v) for v in rb), default=0)
            if not all(close(u, v, scale) for u, v in zip(ra, rb)):
                return False
    return True


def exact_modes(el: Elements) -> ExactModes | None:
    """The modal quantities of an all-elastic scene (every piece tied to a wall) settled in mpmath;
    None where they do not settle by the last of :data:`DIGITS` (repeated frequencies)."""
    import mpmath

    prev = None
    for dps in DIGITS:
        cur = _at(el, dps)
        if prev is not None:
            with mpmath.workdps(dps):
                ok = _settled(prev, cur)
            if ok:
                f = lambda v: np.array([float(u) for u in v])  # noqa: E731  (the one rounding)
                rows = {key: np.array([[float(u) for u in row] for row in cur[key]]).reshape(len(cur["omega"]), -1)
                        for key in _ROWS}
                return ExactModes(*(f(cur[key]) for key in _PER_MODE), rows["shapes"].T, rows["displacement"],
                                  rows["drift"], rows["force"], cur["proportional"], dps)
        prev = cur
    return None


__all__ = ["ExactModes", "exact_modes", "MP_MAX_MASSES"]
