"""Approximate solvers of the singular systems ``(K − λ_j M) v = r`` the refinement iterates with.

Both are only *correctors*: every solution they return is checked and improved against a
residual computed from the elements in double-double (:mod:`.double_double`), so their own
rounding never reaches a result; they must only be close enough to contract.

* :class:`ModalSolver` — any scene whose modes fit in memory: the accurate spring-factor modes
  (:mod:`numeric.spectrum`) give ``(K − λM)`` on the M-orthogonal complement of the cluster
  ``C`` of λ_j: ``v = M^-1/2 Σ_{k∉C} u_k (u_kᵀ M^-1/2 r) / (λ_k − λ_j)`` (O(N²) per solve).
* :class:`ChainSolver` — an open chain: Nelson's own system, the tridiagonal ``K − λ_j M`` with
  the row and column of the twist index ``t`` (the largest mass-weighted component of mode j)
  deleted, ``v_t = 0``: two independent tridiagonal solves above and below ``t``, O(n).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg


class ModalSolver:
    """``(K − λM)⁺`` on the complement of a cluster, from an accurate modal basis.

    Parameters
    ----------
    masses : ndarray, shape (N,)
    vectors : ndarray, shape (N, N)
        Orthonormal mass-weighted modes ``u_k = M^1/2 φ_k`` as columns.
    omega2 : ndarray, shape (N,)
        Their ω² (ascending).
    """

    def __init__(self, masses: np.ndarray, vectors: np.ndarray, omega2: np.ndarray):
        self.root = np.sqrt(np.asarray(masses, dtype=float))
        self.vectors = np.asarray(vectors, dtype=float)
        self.omega2 = np.asarray(omega2, dtype=float)

    def solve(self, r: np.ndarray, lam: float, cluster: np.ndarray) -> np.ndarray:
        """``v`` with ``(K − λM) v = r`` off the cluster and ``v`` M-orthogonal to it.

        Parameters
        ----------
        r : ndarray, shape (N,) or (N, q)
        lam : float
        cluster : ndarray of int
            Mode positions (columns of ``vectors``) left out: λ's own cluster.
        """
        r = np.asarray(r, dtype=float)
        rho = r / (self.root if r.ndim == 1 else self.root[:, None])
        c = self.vectors.T @ rho
        gap = self.omega2 - lam
        keep = np.ones(gap.shape[0], dtype=bool)
        keep[np.asarray(cluster, dtype=np.intp)] = False
        scale = np.where(keep, 1.0 / np.where(keep, gap, 1.0), 0.0)
        c = c * (scale if c.ndim == 1 else scale[:, None])
        w = self.vectors @ c
        return w / (self.root if w.ndim == 1 else self.root[:, None])


class ChainSolver:
    """Nelson's deleted-row system of an open chain (walls or free ends), O(n) per solve.

    Parameters
    ----------
    masses : ndarray, shape (n,)
    position_stiffness : ndarray, shape (n + 1,)
        Spring constant at each chain position: 0 the left wall, p the spring between masses
        p − 1 and p, n the right wall (0 where there is no spring).
    """

    def __init__(self, masses: np.ndarray, position_stiffness: np.ndarray):
        self.masses = np.asarray(masses, dtype=float)
        k = np.asarray(position_stiffness, dtype=float)
        self.n = int(self.masses.shape[0])
        self.diag_k = k[:-1] + k[1:]  # sums of non-negative numbers: each to half an ulp
        self.off = -k[1:-1]

    def _band(self, lam: float, lo: int, hi: int) -> np.ndarray:
        """``K − λM`` rows/columns lo … hi−1 in LAPACK band storage, shape (3, hi − lo)."""
        ab = np.zeros((3, hi - lo))
        ab[1] = self.diag_k[lo:hi] - lam * self.masses[lo:hi]
        ab[0, 1:] = self.off[lo:hi - 1]
        ab[2, :-1] = self.off[lo:hi - 1]
        return ab

    def solve(self, r: np.ndarray, lam: float, twist: int) -> np.ndarray:
        """``v`` with ``v_t = 0`` and every row of ``(K − λM) v = r`` but row ``t`` (NaN where a block is
        exactly singular in float64)."""
        r = np.asarray(r, dtype=float)
        v = np.zeros_like(r)
        for lo, hi in ((0, twist), (twist + 1, self.n)):
            if hi > lo:
                try:
                    v[lo:hi] = scipy.linalg.solve_banded((1, 1), self._band(lam, lo, hi), r[lo:hi],
                                                         check_finite=False)
                except np.linalg.LinAlgError:
                    v[lo:hi] = np.nan
        return v

    def inverse_iteration(self, lam: float, seed: int = 0) -> np.ndarray:
        """A first approximation of the mode at ``λ`` (two steps of inverse iteration with the full
        banded LU), shape (n,)."""
        rng = np.random.default_rng(seed)
        shift = lam
        x = rng.standard_normal(self.n)
        for attempt in range(8):
            ab = self._band(shift, 0, self.n)
            try:
                with np.errstate(all="ignore"):
                    y = scipy.linalg.solve_banded((1, 1), ab, x, check_finite=False)
                    y = scipy.linalg.solve_banded((1, 1), ab, y / np.linalg.norm(y), check_finite=False)
            except np.linalg.LinAlgError:
                y = None
            if y is not None and np.all(np.isfinite(y)) and np.linalg.norm(y) > 0:
                return y / np.linalg.norm(y)
            # λ an exact eigenvalue of the float64 matrix: move the shift by a few ulps
            shift = lam * (1 + 2.0 ** (attempt - 50)) if lam else 2.0 ** (attempt - 1074 + 60)
        return x / np.linalg.norm(x)


__all__ = ["ModalSolver", "ChainSolver"]
