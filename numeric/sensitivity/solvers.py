"""Approximate solvers of the singular systems ``(K − λ_j M) v = r`` the refinement iterates with.

Both are only *correctors*: every solution they return is checked and improved against a
residual computed from the elements in double-double (:mod:`.double_double`), so their own
rounding never reaches a result; they must only be close enough to contract.

* :class:`ModalSolver` — any scene whose modes fit in memory: the accurate spring-factor modes
  (:mod:`numeric.modes.spectrum`) give ``(K − λM)`` on the M-orthogonal complement of the cluster
  ``C`` of λ_j: ``v = M^-1/2 Σ_{k∉C} u_k (u_kᵀ M^-1/2 r) / (λ_k − λ_j)`` (O(N²) per solve).
* :class:`ChainSolver` — an open chain: Nelson's own system, the tridiagonal ``K − λ_j M`` with
  the row and column of the twist index ``t`` (the largest mass-weighted component of mode j)
  deleted, ``v_t = 0``: two independent tridiagonal solves above and below ``t``, O(n).
"""

from __future__ import annotations

import functools

import numpy as np

#: Chains at least this long run the two O(n) recurrences compiled by numba (compiled once, cached on
#: disk); shorter ones in plain Python (no compilation in a small scene's process).
COMPILED_MIN_N = 5000


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


def _series_pivots(k: np.ndarray) -> np.ndarray:
    """Pivots of ``K = L D Lᵀ`` of an open chain (top-down, subtraction-free): ``D_i = w_i + k_{i+1}``
    with ``w_0 = k_0`` and ``w_{i+1} = w_i k_{i+1} / (w_i + k_{i+1})`` — the stiffness from mass i to the
    left wall through the springs before it (springs in series); ``L_{i+1,i} = −k_{i+1}/D_i``.

    Parameters
    ----------
    k : ndarray, shape (n + 1,)
        Spring constant at each position (0 the left wall, n the right wall).
    """
    n = k.shape[0] - 1
    kernel = _compiled("pivots") if n >= COMPILED_MIN_N else None
    if kernel is not None:
        out = np.empty(n)
        kernel(np.ascontiguousarray(k, dtype=float), out)
        return out
    kk = k.tolist()
    D = [0.0] * n
    w = kk[0]
    for i in range(n):
        D[i] = w + kk[i + 1]
        w = w * kk[i + 1] / D[i] if D[i] > 0 else 0.0
    return np.array(D)


def _pivots_kernel(k, D):
    """:func:`_series_pivots` on arrays (the body numba compiles)."""
    n = k.shape[0] - 1
    w = k[0]
    for i in range(n):
        D[i] = w + k[i + 1]
        w = w * k[i + 1] / D[i] if D[i] > 0 else 0.0


def _shifted_kernel(k, D, m, lam, Dp, Lp, tiny):
    """:func:`_shifted` on arrays (the body numba compiles)."""
    n = m.shape[0]
    s = -lam * m[0]
    for i in range(n):
        dp = D[i] + s
        if dp == 0.0:
            dp = tiny
        Dp[i] = dp
        if i < n - 1:
            k1 = k[i + 1]
            Lp[i] = -k1 / dp
            s = (k1 * k1 / (dp * D[i])) * s - lam * m[i + 1] if D[i] > 0 else -lam * m[i + 1]


@functools.lru_cache(maxsize=None)
def _compiled(name: str):
    """The numba-compiled kernel ``name`` (None without numba)."""
    fn = {"pivots": _pivots_kernel, "shifted": _shifted_kernel}[name]
    try:
        import numba

        return numba.njit(cache=True)(fn)
    except Exception:  # no numba, or a numba that fails to load: plain Python
        return None


def _shifted(k: np.ndarray, D: np.ndarray, masses: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """``K − λM = L₊ D₊ L₊ᵀ`` by the stationary qd transform of the representation ``(L, D)`` of K with
    the diagonal shift ``λ m_i`` (dstqds of LAPACK's MRRR, generalised to a diagonal shift):
    ``D₊_i = D_i + s_i``, ``L₊_i = −k_{i+1}/D₊_i``, ``s_{i+1} = k_{i+1}² s_i / (D₊_i D_i) − λ m_{i+1}``,
    ``s_0 = −λ m_0``. Mixed relatively stable: the pivots are those of a chain with relatively perturbed
    springs and masses, so small λ next to stiff springs keep their accuracy (a float64 LU of ``K − λM``
    does not). Zero pivots become ±tiny."""
    n = masses.shape[0]
    kernel = _compiled("shifted") if n >= COMPILED_MIN_N else None
    if kernel is not None:
        Dp, Lp = np.empty(n), np.empty(max(n - 1, 0))
        kernel(k, D, masses, float(lam), Dp, Lp, np.finfo(float).tiny)
        return Dp, Lp
    kk, dd, mm = k.tolist(), D.tolist(), masses.tolist()
    Dp = [0.0] * n
    Lp = [0.0] * max(n - 1, 0)
    tiny = np.finfo(float).tiny
    s = -lam * mm[0]
    for i in range(n):
        dp = dd[i] + s
        if dp == 0.0:
            dp = tiny
        Dp[i] = dp
        if i < n - 1:
            k1 = kk[i + 1]
            Lp[i] = -k1 / dp
            s = (k1 * k1 / (dp * dd[i])) * s - lam * mm[i + 1] if dd[i] > 0 else -lam * mm[i + 1]
    return np.array(Dp), np.array(Lp)


class ChainSolver:
    """Nelson's deleted-row system of an open chain (walls or free ends), O(n) per solve.

    ``K − λM`` with row and column t deleted splits into its leading block (masses 0 … t−1) and trailing
    block (t+1 … n−1). The leading block's factorisation is the first t steps of the stationary qd
    transform of K's subtraction-free ``LDLᵀ`` (:func:`_shifted`); the trailing block's, the same on the
    reversed chain. Each solve is then two LAPACK ``dpttrs`` substitutions.

    Parameters
    ----------
    masses : ndarray, shape (n,)
    position_stiffness : ndarray, shape (n + 1,)
        Spring constant at each chain position: 0 the left wall, p the spring between masses
        p − 1 and p, n the right wall (0 where there is no spring).
    """

    def __init__(self, masses: np.ndarray, position_stiffness: np.ndarray):
        self.masses = np.asarray(masses, dtype=float)
        self.k = np.asarray(position_stiffness, dtype=float)
        self.n = int(self.masses.shape[0])
        self.off = -self.k[1:-1]  # K_{i,i+1}
        self._D = _series_pivots(self.k)
        self._Dr = _series_pivots(self.k[::-1].copy())
        self._lam = None

    def _prepare(self, lam: float) -> None:
        # a corrector needs no exact shift: λ refined by a few ulps keeps the factorisation (two O(n) passes)
        if self._lam is None or abs(lam - self._lam) > 1e-12 * abs(lam):
            self._top = _shifted(self.k, self._D, self.masses, lam)
            self._bottom = _shifted(self.k[::-1].copy(), self._Dr, self.masses[::-1].copy(), lam)
            self._lam = lam

    @staticmethod
    def _pt(D: np.ndarray, L: np.ndarray, size: int, b: np.ndarray) -> np.ndarray:
        from scipy.linalg.lapack import dpttrs

        if size == 1:
            return b / D[0]
        x, info = dpttrs(D[:size], L[:size - 1], b)
        return x if info == 0 else np.full_like(b, np.nan)

    def solve(self, r: np.ndarray, lam: float, twist: int) -> np.ndarray:
        """``v`` with ``v_t = 0`` and every row of ``(K − λM) v = r`` but row ``t``."""
        self._prepare(lam)
        r = np.asarray(r, dtype=float)
        v = np.zeros_like(r)
        t, n = twist, self.n
        if t > 0:
            v[:t] = self._pt(*self._top, t, np.ascontiguousarray(r[:t]))
        if t < n - 1:
            v[t + 1:] = self._pt(*self._bottom, n - t - 1, np.ascontiguousarray(r[t + 1:][::-1]))[::-1]
        return v

    def twist(self, lam: float) -> int:
        """The twist index: where ``γ_k = D₊_k + D₋_k − (K_kk − λ m_k)`` is smallest in magnitude (the
        mode's largest component, MRRR's choice)."""
        self._prepare(lam)
        diag = self.k[:-1] + self.k[1:] - lam * self.masses
        gamma = self._top[0] + self._bottom[0][::-1] - diag
        return int(np.argmin(np.abs(gamma)))

    def vector(self, lam: float) -> tuple[np.ndarray, int]:
        """The mode at ``λ`` with ``x_t = 1`` at the twist index t (every row but t of ``(K − λM)x = 0``)."""
        t = self.twist(lam)
        col = np.zeros(self.n)
        if t > 0:
            col[t - 1] = -self.off[t - 1]
        if t < self.n - 1:
            col[t + 1] = -self.off[t]
        x = self.solve(col, lam, t)
        x[t] = 1.0
        return x, t


__all__ = ["ModalSolver", "ChainSolver"]
