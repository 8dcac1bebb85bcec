"""One-sided (Hestenes) Jacobi SVD of many small complex matrices at once.

For X of shape (Q, n, p), rotations of column pairs make the columns of X V orthogonal; the singular values
are then the column norms, computed as sums of squares. For X = B Δ with Δ a column scaling and B well
conditioned (the Bloch factor of :mod:`.factor`), each singular value comes out with a relative error of a few
ulps times κ(B), whatever Δ's range (Demmel & Veselić, SIAM J. Matrix Anal. Appl. 13, 1992) — unlike a
bidiagonalising SVD or ``eigh`` of X Xᴴ, whose errors are relative to the largest one.

With numba (a dependency on CPython) each matrix is rotated to convergence by a compiled loop
(:func:`_jacobi_impl`, ``numba.njit(cache=True)``: compiled once, kept on disk); without it every pair is
rotated for all Q matrices at once in NumPy (:func:`_jacobi_numpy`), the converged ones by the identity. Both
apply the same rotations and the same convergence test.
"""

from __future__ import annotations

import functools

import numpy as np

#: Sweeps before giving up (quadratic convergence: a handful are used).
MAX_SWEEPS = 60


def _jacobi_impl(X, V, tol, max_sweeps):  # pragma: no cover - compiled by numba (the NumPy twin is tested)
    """Rotate each X[q] (and V[q]) in place until its columns are orthogonal; returns the unconverged count."""
    Q, n, p = X.shape
    failed = 0
    for k in range(Q):
        converged = False
        for _ in range(max_sweeps):
            rotated = False
            for i in range(p - 1):
                for j in range(i + 1, p):
                    a = 0.0
                    b = 0.0
                    g = 0.0 + 0.0j
                    for r in range(n):
                        xi = X[k, r, i]
                        xj = X[k, r, j]
                        a += xi.real * xi.real + xi.imag * xi.imag
                        b += xj.real * xj.real + xj.imag * xj.imag
                        g += xi.conjugate() * xj
                    ag = abs(g)
                    if not ag > tol * np.sqrt(a) * np.sqrt(b):
                        continue
                    zeta = (b - a) / (2.0 * ag)
                    # hypot: zeta reaches 1e170 when the columns' norms span 1e160 (zeta**2 would overflow
                    # and make t = 0, a rotation that never ends); t = 0 (zeta = inf) is converged
                    t = (1.0 if zeta >= 0 else -1.0) / (abs(zeta) + np.hypot(1.0, zeta))
                    if t == 0.0:
                        continue
                    rotated = True
                    c = 1.0 / np.sqrt(1.0 + t * t)
                    s = c * t
                    ph = (g / ag).conjugate()
                    for r in range(n):
                        mi = X[k, r, i]
                        mj = X[k, r, j] * ph
                        X[k, r, i] = c * mi - s * mj
                        X[k, r, j] = s * mi + c * mj
                    for r in range(p):
                        mi = V[k, r, i]
                        mj = V[k, r, j] * ph
                        V[k, r, i] = c * mi - s * mj
                        V[k, r, j] = s * mi + c * mj
            if not rotated:
                converged = True
                break
        if not converged:
            failed += 1
    return failed


@functools.lru_cache(maxsize=1)
def _kernel():
    from ..compiled.fast_kernels import available

    if available():
        import numba

        return numba.njit(cache=True)(_jacobi_impl)
    return None


def jacobi(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(XV, V)``: X rotated until its columns are orthogonal, and the unitary V, each (Q, n, p).

    Raises
    ------
    ArithmeticError
        If some matrix has not converged after :data:`MAX_SWEEPS` sweeps (not seen on finite input).
    """
    X = np.array(X, dtype=complex, copy=True)
    kernel = _kernel()
    if kernel is None:
        return _jacobi_numpy(X)
    Q, n, p = X.shape
    V = np.zeros((Q, p, p), dtype=complex)
    V[:, np.arange(p), np.arange(p)] = 1.0
    if kernel(X, V, max(n, 1) * np.finfo(float).eps, MAX_SWEEPS):
        raise ArithmeticError(f"one-sided Jacobi did not converge in {MAX_SWEEPS} sweeps")
    return X, V


def _jacobi_numpy(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`jacobi` without numba: every pair rotated for all Q matrices at once."""
    Q, n, p = X.shape
    V = np.broadcast_to(np.eye(p, dtype=complex), (Q, p, p)).copy()
    tol = max(n, 1) * np.finfo(float).eps
    for _ in range(MAX_SWEEPS):
        rotated = False
        for i in range(p - 1):
            for j in range(i + 1, p):
                xi, xj = X[:, :, i], X[:, :, j]
                a = np.einsum("qk,qk->q", xi.real, xi.real) + np.einsum("qk,qk->q", xi.imag, xi.imag)
                b = np.einsum("qk,qk->q", xj.real, xj.real) + np.einsum("qk,qk->q", xj.imag, xj.imag)
                g = np.einsum("qk,qk->q", xi.conj(), xj)
                ag = np.abs(g)
                do = ag > tol * np.sqrt(a) * np.sqrt(b)
                if not do.any():
                    continue
                with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
                    zeta = (b - a) / (2.0 * ag)
                t = np.where(zeta >= 0, 1.0, -1.0) / (np.abs(zeta) + np.hypot(1.0, zeta))  # as in _jacobi_impl
                do &= t != 0.0
                if not do.any():
                    continue
                rotated = True
                idx = np.flatnonzero(do)
                a, b, g, ag, t = a[idx], b[idx], g[idx], ag[idx], t[idx]
                c = 1.0 / np.sqrt(1.0 + t * t)
                s = c * t
                ph = np.conj(g / ag)  # e^{-iφ}: x̃_j = e^{-iφ} x_j makes x_iᴴ x̃_j real
                for M in (X, V):
                    mi, mj = M[idx, :, i], M[idx, :, j] * ph[:, None]
                    M[idx, :, i] = c[:, None] * mi - s[:, None] * mj
                    M[idx, :, j] = s[:, None] * mi + c[:, None] * mj
        if not rotated:
            return X, V
    raise ArithmeticError(f"one-sided Jacobi did not converge in {MAX_SWEEPS} sweeps")


__all__ = ["MAX_SWEEPS", "jacobi"]
