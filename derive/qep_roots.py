"""Eigenvalues of the damped modal problem ``det(λ² I + λ G + diag(ω²)) = 0`` in mpmath, by Newton's method.

The state matrix ``[[0, I], [−diag(ω²), −G]]`` of size 2m has the same 2m eigenvalues. ``mpmath.eig`` finds
them by Hessenberg QR in complex mpmath arithmetic, ~0.5 s for m = 12 at each precision (two precisions
per report). Here LAPACK's float64 eigenvalues of the balanced form ``[[0, Ω], [−Ω, −G]]`` are only the
starting points: each is refined by Newton's method on ``det Q(λ)`` at the working precision,
``λ ← λ − 1 / tr(Q(λ)⁻¹ Q'(λ))`` with ``Q' = 2λ I + G`` (one m × m complex elimination per step).

The roots come in conjugate pairs (real coefficients): the starts in the upper half-plane and the real
ones are refined, their conjugates taken. The next precision starts from the roots found at the previous
one (one or two steps). The result is accepted only when every start converged (last step below ``10^(−dps/2)`` of |λ|) to a
root (near 0: within ``10^(−dps)`` of the largest |λ|) and the 2m roots are pairwise distinct by far more than that: 2m distinct roots of a polynomial
of degree 2m are all of its roots. Anything else (a repeated or nearly repeated eigenvalue, where
Newton converges slowly or two starts meet; a start that does not converge) returns None and the
caller uses ``mpmath.eig``. The caller's accuracy check (two precisions agreeing) is unchanged.
"""

from __future__ import annotations

import mpmath
import numpy as np

#: Newton steps per start before giving up (quadratic convergence from a float64 start: 3–6 at 80 digits).
MAX_STEPS = 40


def _newton_step(lam, w2: list, G: list, m: int):
    """``1 / tr(Q(λ)⁻¹ Q'(λ))`` at ``lam`` (Gaussian elimination with partial pivoting on lists, all m
    columns of Q' at once), or None when Q(λ) is exactly singular at this precision."""
    rows = [[lam * G[i][j] for j in range(m)] + [G[i][j] for j in range(m)] for i in range(m)]  # [Q | Q']
    for i in range(m):
        rows[i][i] += lam * lam + w2[i]
        rows[i][m + i] += 2 * lam
    for c in range(m):
        p = max(range(c, m), key=lambda r: abs(rows[r][c]))
        if rows[p][c] == 0:
            return None
        rows[c], rows[p] = rows[p], rows[c]
        piv = rows[c]
        inv = 1 / piv[c]
        for r in range(c + 1, m):
            f = rows[r][c] * inv
            if f:
                row = rows[r]
                for q in range(c + 1, 2 * m):
                    row[q] -= f * piv[q]
    # back substitution for the diagonal of X = Q⁻¹ Q' only needs every column's full solve
    tr = 0
    for col in range(m):
        x = [0] * m
        for i in reversed(range(m)):
            acc = rows[i][m + col]
            for j in range(i + 1, m):
                acc -= rows[i][j] * x[j]
            x[i] = acc / rows[i][i]
        tr += x[col]
    return None if tr == 0 else 1 / tr


def qep_roots(w2: list, G, dps: int) -> list | None:
    """The 2m eigenvalues of ``λ² I + λ G + diag(w2)`` at ``dps`` digits, or None (see the module docstring).

    Parameters
    ----------
    w2 : list of mpmath.mpf, length m
        ω² of the modes kept (≥ 0).
    G : mpmath.matrix, shape (m, m)
        Modal damping matrix ΦᵀCΦ of those modes.
    dps : int
        Working precision (decimal digits).

    Returns
    -------
    list of mpmath.mpc, length 2m, or None
    """
    m = len(w2)
    if m == 0:
        return []
    Om = np.sqrt(np.maximum(np.array([float(w) for w in w2]), 0.0))
    Gf = np.array([[float(G[i, j]) for j in range(m)] for i in range(m)])
    if not (np.all(np.isfinite(Om)) and np.all(np.isfinite(Gf))):
        return None
    key = (Om.tobytes(), Gf.tobytes())
    starts = _STARTS.get(key)
    if starts is None:
        A = np.block([[np.zeros((m, m)), np.diag(Om)], [-np.diag(Om), -Gf]])
        starts = [complex(s) for s in np.linalg.eigvals(A)]
    # real coefficients: the roots come in conjugate pairs; refine the upper half (and the real ones) only
    upper = [s for s in starts if s.imag > 0]
    real = [s for s in starts if s.imag == 0 or (s.imag < 0 and abs(s.imag) <= 1e-12 * abs(s))]
    real = [complex(s.real, 0.0) for s in real]
    if 2 * len(upper) + len(real) != 2 * m:
        return None
    Gl = [[G[i, j] for j in range(m)] for i in range(m)]
    with mpmath.workdps(dps):
        tol = mpmath.mpf(10) ** (-(dps // 2))
        # a root at (or within 10^-dps of the spectrum's scale from) 0 is settled absolutely there
        floor = tol * max(abs(s) for s in starts)
        found = []
        for s in upper + real:
            lam = mpmath.mpc(s.real, s.imag)
            for _ in range(MAX_STEPS):
                step = _newton_step(lam, w2, Gl, m)
                if step is None:  # landed on the root exactly (Q singular)
                    break
                lam -= step
                if abs(step) <= tol * max(abs(lam), floor):
                    break
            else:
                return None
            found.append(lam)
        roots = []
        for lam in found[:len(upper)]:
            roots += [lam, mpmath.conj(lam)]
        roots += found[len(upper):]
        scale = max(abs(r) for r in roots) or mpmath.mpf(1)
        sep = mpmath.mpf(10) ** (-(dps // 4)) * scale
        for i in range(len(roots)):
            for j in range(i + 1, len(roots)):
                if abs(roots[i] - roots[j]) <= sep:
                    return None
        if len(_STARTS) > 64:
            _STARTS.clear()
        _STARTS[key] = [complex(r) for r in roots]  # the next precision starts here
        return roots


#: Roots found last for a problem (keyed by its float64 data): the starting points at the next precision.
_STARTS: dict = {}


__all__ = ["qep_roots"]
