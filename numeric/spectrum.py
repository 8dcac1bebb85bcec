"""Frequencies and modes of ``K φ = ω² M φ`` by the accurate route.

``D = M^-1/2 K M^-1/2 = GᵀG`` with the spring factor ``G = diag(√k) B M^-1/2``
(``B``: spring–mass incidence, walls included). Forming ``D`` (or ``M⁻¹K``)
adds a small spring to a large one and rounds it away; the singular values
of ``G`` are the frequencies ω themselves and lose nothing to that sum.

Rigid-body modes are taken by structure, not by a threshold: every free
connected piece (no spring to a wall) has exactly one ω = 0 mode, the
uniform translation of that piece. ``G`` is restricted to the orthogonal
complement of those translations before the SVD, so the zeros are exact
and the remaining ω are all positive.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


@dataclass(frozen=True)
class Spectrum:
    """Modes of a linear chain.

    Attributes
    ----------
    omega : ndarray, shape (N,)
        Angular frequencies, ascending; exact zeros first for rigid-body modes.
    vectors : ndarray, shape (N, N)
        Orthonormal eigenvectors of D (mass-weighted), columns in ``omega`` order.
    masses : ndarray, shape (N,)
    rigid : int
        Number of rigid-body modes (free connected pieces).
    """

    omega: np.ndarray = field(repr=False)
    vectors: np.ndarray = field(repr=False)
    masses: np.ndarray = field(repr=False)
    rigid: int

    @property
    def omega2(self) -> np.ndarray:
        return self.omega**2

    @property
    def shapes(self) -> np.ndarray:
        """Physical, M-orthonormal mode shapes ``M^-1/2 e`` as columns, shape (N, N)."""
        return self.vectors / np.sqrt(self.masses)[:, None]

    @property
    def omega_max(self) -> float:
        return float(self.omega[-1]) if self.omega.size else 0.0

    def residual(self, K: np.ndarray) -> float:
        """Relative residual ‖D V − V Λ‖ / ‖D‖ (a check, not used by the solution)."""
        s = 1 / np.sqrt(self.masses)
        D = K * s[:, None] * s[None, :]
        R = D @ self.vectors - self.vectors * self.omega2[None, :]
        return float(np.linalg.norm(R) / max(np.linalg.norm(D), np.finfo(float).tiny))


def incidence(n: int, ends: np.ndarray) -> np.ndarray:
    """Spring–mass incidence matrix B, shape (S, N): +1 at end a, -1 at end b (walls omitted)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    B = np.zeros((ends.shape[0], n))
    rows = np.arange(ends.shape[0])
    a, b = ends[:, 0], ends[:, 1]
    np.add.at(B, (rows[a >= 0], a[a >= 0]), 1.0)
    np.add.at(B, (rows[b >= 0], b[b >= 0]), -1.0)
    return B


def spring_factor(masses: np.ndarray, ends: np.ndarray, k: np.ndarray) -> np.ndarray:
    """``G = diag(√k) B M^-1/2`` with ``GᵀG = D``, shape (S, N)."""
    B = incidence(masses.shape[0], ends)
    return np.sqrt(k)[:, None] * B / np.sqrt(masses)[None, :]


def free_pieces(n: int, ends: np.ndarray) -> list[np.ndarray]:
    """Index arrays of the connected pieces with no spring to a wall."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    inner = (ends[:, 0] >= 0) & (ends[:, 1] >= 0)
    graph = coo_matrix((np.ones(int(inner.sum())), (ends[inner, 0], ends[inner, 1])), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    walled = np.zeros(count, dtype=bool)
    wall_rows = ~inner
    touched = np.where(ends[wall_rows, 0] >= 0, ends[wall_rows, 0], ends[wall_rows, 1])
    walled[labels[touched]] = True
    return [np.flatnonzero(labels == c) for c in range(count) if not walled[c]]


def rigid_basis(masses: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Orthonormal mass-weighted rigid-body vectors, one column per free piece, shape (N, r)."""
    n = masses.shape[0]
    pieces = free_pieces(n, ends)
    R = np.zeros((n, len(pieces)))
    for j, idx in enumerate(pieces):  # loop over pieces, not masses
        w = np.sqrt(masses[idx])
        R[idx, j] = w / np.linalg.norm(w)
    return R


def spectrum(masses: np.ndarray, ends: np.ndarray, k: np.ndarray) -> Spectrum:
    """Frequencies and modes from the SVD of the spring factor, rigid modes by structure.

    Parameters
    ----------
    masses : ndarray, shape (N,)
    ends : ndarray of int, shape (S, 2)
        Spring ends, -1 for a wall.
    k : ndarray, shape (S,)
        Spring constants.
    """
    masses = np.asarray(masses, dtype=float)
    n = masses.shape[0]
    R = rigid_basis(masses, ends)
    r = R.shape[1]
    G = spring_factor(masses, ends, np.asarray(k, dtype=float))
    if r:
        # orthonormal basis of the complement of the rigid translations
        Q_full, _ = np.linalg.qr(np.hstack([R, np.eye(n)]))
        Q = Q_full[:, r:n]
        # re-orthogonalise against R to roundoff
        Q -= R @ (R.T @ Q)
        Q, _ = np.linalg.qr(Q)
    else:
        Q = np.eye(n)
    if n - r:
        _, s, vt = scipy.linalg.svd(G @ Q, full_matrices=True, lapack_driver="gesvd")
        s_full = np.zeros(n - r)
        s_full[: s.shape[0]] = s[: n - r]
        V = Q @ vt.T[:, : n - r]
        order = np.argsort(s_full, kind="stable")
        omega_el, V = s_full[order], V[:, order]
    else:
        omega_el, V = np.zeros(0), np.zeros((n, 0))
    omega = np.concatenate([np.zeros(r), omega_el])
    vectors = np.hstack([R, V])
    return Spectrum(omega, vectors, masses, r)


def spectrum_from_closed_form(omega2: np.ndarray, shapes: np.ndarray, masses: np.ndarray,
                              rigid: int) -> Spectrum:
    """A :class:`Spectrum` from generated closed forms (ω² and physical shapes, any scale).

    Shapes are M-orthonormalised (a QR in mass-weighted coordinates, in ascending
    ω² order) so repeated frequencies get an orthonormal basis; ω² that roundoff
    pushed below zero is clipped (ω = √max(ω², 0)).
    """
    order = np.argsort(omega2, kind="stable")
    w2 = np.maximum(np.asarray(omega2, dtype=float)[order], 0.0)
    w2[:rigid] = 0.0
    E = np.sqrt(masses)[:, None] * np.asarray(shapes, dtype=float)[:, order]
    Qm, Rm = np.linalg.qr(E)
    Qm = Qm * np.sign(np.diag(Rm))[None, :]
    return Spectrum(np.sqrt(w2), Qm, np.asarray(masses, dtype=float), rigid)
