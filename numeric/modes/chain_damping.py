"""Damping ratios of a ``[chain]``'s modes: ζ, ω_n and ω_d per mode, from an accurate route.

A chain lists all its damping as dashpots (its ``[[dampers]]`` and Rayleigh's α·m to the ground
and β·k beside every spring), so one route serves every chain of at most :data:`DENSE_MAX`
masses, as :mod:`derive.damping_report` does for ``[masses]`` scenes past mpmath's size:

1. Φ, ω from the spring-factor SVD (:mod:`numeric.modes.spectrum`: relatively accurate at any
   contrast, rigid modes exact by structure) and ``G = ΦᵀCΦ`` from the dashpots' stretches
   (:func:`numeric.modes.elements.modal_damping`);
2. the eigenvalues λ = −σ ± iω_d of the balanced modal state matrix ``[[0, Ω], [−Ω, −G]]`` by
   LAPACK, each pair then refined by Newton's method with residuals in extended precision
   (:func:`numeric.exact.linear.refine_small`; states of at most :data:`REFINE_MAX_STATES`), so a
   light ζ of a low mode is not lost in ε·ω_max; modes of a piece the dashpots do not touch (a zero row of G) are undamped by
   structure, ζ = 0 exactly.

ω_n = |λ|, ζ = σ/ω_n. Where σ is below 1e-10 of its float64 resolution (:data:`RESOLVED`: a mode
all but confined away from every dashpot at a contrast of 1e10, ζ = 1e-34; or a light mode beside a
heavy dashpot, whose ε‖G‖ is large), a chain of at most :data:`MP_MAX` masses takes ζ from the state
matrix's eigenvalues in mpmath, settled by doubling the digits; what stays unsettled, or a longer
chain's, is NaN (said, not printed); rigid modes have ζ None; an overdamped pair (two real eigenvalues r₁, r₂
of one mode: the one that carries most of their eigenvectors, :func:`_real_pairs`) gives ω_n = √(r₁r₂),
ζ = −(r₁ + r₂)/(2ω_n), ω_d = 0. Longer chains are the caller's to refuse
(a Rayleigh-only chain has ζ_j = α/(2ω_j) + βω_j/2 in closed form at any length).
"""

from __future__ import annotations

import numpy as np

#: Largest chain whose damped modes are computed from the dense modal state matrix (2N states).
DENSE_MAX = 60
#: A decay rate σ is resolved when above this many ε·max|G| (its float64 uncertainty, 1e-10 relative).
RESOLVED = 1e10 * 64
#: Largest state (2N) whose eigenpairs are refined in extended precision (Python-level mpmath
#: residuals: 8 s at 40 states); larger ones keep LAPACK's values with the floor widened to ε‖A‖.
REFINE_MAX_STATES = 24
#: Chains of at most this many masses get the ζ float64 leaves unresolved from mpmath (2N states).
MP_MAX = 12
#: The most digits that settling tries (40, 80, 160, 320).
MP_MAX_DIGITS = 320
_EPS = float(np.finfo(float).eps)


def damped_rows(masses: np.ndarray, spring_ends: np.ndarray, stiffness: np.ndarray,
                damper_ends: np.ndarray, damping: np.ndarray) -> list[tuple]:
    """``(ω_n, ζ, ω_d)`` per mode, ascending ω_n (ζ None for a rigid mode); length N.

    Parameters
    ----------
    masses : ndarray, shape (N,)
    spring_ends, damper_ends : ndarray of int, shape (S, 2) and (D, 2)
        Mass indices, -1 for a wall.
    stiffness, damping : ndarray, shape (S,) and (D,)
    """
    import scipy.linalg

    from .elements import Elements, modal_damping
    from ..exact.linear import refine_small
    from .spectrum import spectrum

    el = Elements(np.asarray(masses, dtype=float), np.asarray(spring_ends, dtype=np.intp).reshape(-1, 2),
                  np.asarray(stiffness, dtype=float), np.asarray(damper_ends, dtype=np.intp).reshape(-1, 2),
                  np.asarray(damping, dtype=float))
    spec = spectrum(el.masses, el.spring_ends, el.stiffness)
    w = spec.omega
    G = modal_damping(el, w, spec.shapes)
    n = w.shape[0]
    touched = np.any(G != 0, axis=1)
    rows = [(0.0, None, 0.0)] * int(np.count_nonzero(~touched & (w == 0)))  # undamped rigid modes
    rows += [(float(w[j]), 0.0, float(w[j])) for j in np.flatnonzero(~touched & (w > 0))]  # by structure
    kept = np.flatnonzero(touched)
    m = kept.shape[0]
    if m:  # a damped rigid mode (a dashpot to the wall on a free piece) enters with scale 1: λ = 0 and −g
        A = np.zeros((2 * m, 2 * m))
        A[np.arange(m), m + np.arange(m)] = np.where(w[kept] > 0, w[kept], 1.0)
        A[m + np.arange(m), np.arange(m)] = -w[kept]
        A[m:, m:] = -G[np.ix_(kept, kept)]
        lam, V = scipy.linalg.eig(A)
        refined = A.shape[0] <= REFINE_MAX_STATES
        if refined:
            lam, V = refine_small(A, lam, V.astype(complex), -1.0)  # (all-real λ: V comes real)
        # oscillatory: relative to |λ| (a light mode's λ ~ 1e-11 beside λ ~ 1 is no zero)
        osc = sorted((v for v in lam if v.imag > 1e-12 * abs(v)), key=abs)
        # G's entries are float64 products of the modes (normwise accurate): Re λ is known to about
        # ε‖G‖ (refined) or ε‖A‖ (LAPACK alone), so a ζ whose σ is below RESOLVED times that is not
        # resolved and given as NaN (said, never printed)
        norm = float(np.max(np.abs(G))) if refined else float(np.max(np.sum(np.abs(A), axis=1)))
        floor = RESOLVED * _EPS * norm
        rows += [(float(abs(v)), float(-v.real / abs(v)) if -v.real > floor else float("nan"), float(v.imag))
                 for v in osc]
        real_at = np.flatnonzero(np.abs(lam.imag) <= 1e-12 * np.abs(lam))
        pairs = _real_pairs(lam.real[real_at], V[:, real_at], m)
        if pairs is not None:  # each mode's own two real eigenvalues (by the eigenvectors' modal weights)
            for j, (r1, r2) in pairs:
                rows.append(_overdamped_row(r1, r2) if w[kept[j]] > 0 else (0.0, None, 0.0))
        else:  # modes mixed beyond telling apart: a damped rigid mode takes λ = 0 and −g, then slowest with fastest
            real = sorted((float(v) for v in lam.real[real_at]), key=abs)
            zeros = int(np.count_nonzero(w[kept] == 0))
            rows += [(0.0, None, 0.0)] * zeros
            rest = sorted(real[zeros:], key=lambda r: -r)
            while len(rest) >= 2:
                r1, r2 = rest.pop(0), rest.pop(-1)
                rows.append(_overdamped_row(r1, r2))
    rows.sort(key=lambda r: r[0])
    rows = rows[:n]
    if el.n <= MP_MAX and any(z is not None and z != z for _, z, _ in rows):
        rows = _settle_unresolved(el, rows)
    return rows


def _overdamped_row(r1: float, r2: float) -> tuple:
    """``(ω_n, ζ, 0)`` of an overdamped pair of real eigenvalues: ω_n = √(r₁r₂), ζ = −(r₁ + r₂)/(2ω_n)
    (a pair with a rounding zero has no ω_n: a rigid row)."""
    wn = float(np.sqrt(r1 * r2)) if r1 * r2 > 0 else 0.0
    return (wn, float(-(r1 + r2) / (2 * wn)), 0.0) if wn > 0 else (0.0, None, 0.0)


def _real_pairs(real: np.ndarray, vectors: np.ndarray, m: int) -> list[tuple] | None:
    """The real eigenvalues of the modal state matrix ``[[0, Ω], [−Ω, −G]]`` (2m states) grouped by mode:
    ``[(j, (r₁, r₂)), …]`` with j the mode (0 … m−1) whose coordinates ``(ω̂ q_j, q̇_j)`` carry the most
    of each eigenvector, two per mode (an optimal assignment), or None when some mode gets only one.

    With proportional damping (G diagonal) each eigenvector lies in one mode and the pair is that mode's
    roots of λ² + g_j λ + ω_j² = 0 exactly; pairing by value (the slowest with the fastest) mixed modes
    (a chain with C = 3M: the ω² = 1 mode's −0.38 taken with the rigid mode's −3, ζ = 1.58 for 1.5).
    """
    if real.shape[0] == 0:
        return []
    from scipy.optimize import linear_sum_assignment

    weight = np.abs(vectors[:m]) ** 2 + np.abs(vectors[m:2 * m]) ** 2  # (m, R)
    weight = weight / np.maximum(np.sum(weight, axis=0), np.finfo(float).tiny)
    cost = -np.repeat(weight.T, 2, axis=1)  # (R, 2m): two slots per mode
    rows, cols = linear_sum_assignment(cost)
    mode_of = {int(r): int(c) // 2 for r, c in zip(rows, cols)}
    groups: dict[int, list[float]] = {}
    for r in range(real.shape[0]):
        groups.setdefault(mode_of[r], []).append(float(real[r]))
    if any(len(g) != 2 for g in groups.values()):
        return None
    return [(j, tuple(g)) for j, g in sorted(groups.items())]


def _mp_eigenvalues(el, dps: int) -> list:
    """Eigenvalues of the state matrix ``[[0, I], [−D, −M^-1/2 C M^-1/2]]`` assembled exactly from the
    elements (float inputs read as exact rationals) and solved by mpmath at ``dps`` digits."""
    import mpmath

    from ..frf.dense import to_mp, mp_stamp

    n = el.n
    with mpmath.workdps(dps):
        r = [1 / mpmath.sqrt(to_mp(m, mpmath)) for m in el.masses.tolist()]
        A = mpmath.zeros(2 * n, 2 * n)
        for i in range(n):
            A[i, n + i] = 1
        mp_stamp(A, el.spring_ends, el.stiffness, r, mpmath, row=n, col=0, sign=-1)
        mp_stamp(A, el.damper_ends, el.damping, r, mpmath, row=n, col=n, sign=-1)
        return list(mpmath.eig(A, left=False, right=False))


def _settle_unresolved(el, rows: list[tuple]) -> list[tuple]:
    """Rows whose ζ float64 leaves unresolved (NaN) get it from the state matrix's eigenvalues in mpmath
    at doubling precision (40 … :data:`MP_MAX_DIGITS` digits): the eigenvalue nearest the row's
    ``i·ω_d``, accepted once two precisions agree on ζ to 1e-20 relative; else it stays NaN."""
    import mpmath

    def zeta_of(lam, wd):  # of the eigenvalue nearest the row's i·ω_d (upper half-plane)
        v = min((v for v in lam if v.imag > 0), key=lambda v: abs(complex(v) - 1j * wd), default=None)
        return None if v is None else -v.real / abs(v)

    todo = [k for k, (_, z, _) in enumerate(rows) if z is not None and z != z]
    prev, dps = None, 40
    while todo and dps <= MP_MAX_DIGITS:
        lam = _mp_eigenvalues(el, dps)
        now = {k: zeta_of(lam, rows[k][2]) for k in todo}
        if prev is not None:
            for k in list(todo):
                a, b = now[k], prev[k]
                if a is not None and b is not None and a > 0 and abs(a - b) <= mpmath.mpf("1e-20") * abs(a):
                    rows[k] = (rows[k][0], float(a), rows[k][2])
                    todo.remove(k)
        prev, dps = now, 2 * dps
    return rows


__all__ = ["DENSE_MAX", "damped_rows"]


def chain_damped_rows(system) -> list[tuple] | None:
    """``(ω_n, ζ, ω_d)`` of every mode of a :class:`~springchain.numeric.system.System` chain with dashpots of
    at most :data:`DENSE_MAX` masses (:func:`damped_rows`), else None."""
    if system.n > DENSE_MAX:
        return None
    from .elements import Elements

    el = Elements.from_system(system)
    return damped_rows(el.masses, el.spring_ends, el.stiffness, el.damper_ends, el.damping)
