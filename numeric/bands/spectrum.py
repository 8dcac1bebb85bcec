"""ω²_j(q), eigenvectors and group velocities of a cell, accurate at any contrast; branches by continuity.

:func:`spectrum` runs the Bloch factor (:mod:`.factor`) and the one-sided Jacobi SVD (:mod:`.jacobi`) on |q|
(the bands are even: D(−q) = conj D(q), so ω(−q) = ω(q), eigenvectors conjugate, v_g(−q) = −v_g(q)):

* ω²_j = Σ |column j of XV|² (a sum of squares), ascending at each q; exactly 0 at q = 0 for each piece of
  the cell without a ground spring (its pivot is 0 by structure, never a rounded value);
* eigenvectors of D(q): the normalised columns of XV (physical shapes: M^-1/2 times them);
* dω_j/dq = Re(u_jᴴ X' v_j) — no division by ω — and, where ω = 0 (q = 0), the long-wave limit
  sqrt(K_eff / M_piece), the sound speed in cells per second (the right-hand limit; −q gives its negative).

:func:`by_continuity` reorders the branches along q by eigenvector overlap, so that branches that cross keep
their identity (sorting would swap them at every crossing).
"""

from __future__ import annotations

import numpy as np

from ..array_record import array_record
from .cell import Cell
from .factor import factor
from .jacobi import jacobi

#: Relative gap below which two ω² count as degenerate when following branches.
DEGENERATE = 1e-9


@array_record
class Spectrum:
    """The bands of a cell at some q.

    Attributes
    ----------
    q : ndarray, shape (Q,)
        Phase per cell [rad], as given.
    omega2 : ndarray, shape (Q, p)
        ω²_j(q) [rad²/s²] (ascending at each q, or by continuity after :func:`by_continuity`).
    vectors : ndarray, shape (Q, p, p), complex
        Unit eigenvectors of D(q) as columns, in ``omega2`` order.
    velocity : ndarray, shape (Q, p)
        Group velocity dω_j/dq [cells/s] (q is the phase per cell).
    """

    q: np.ndarray
    omega2: np.ndarray
    vectors: np.ndarray
    velocity: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """ω_j(q) = sqrt(ω²_j) [rad/s], shape (Q, p)."""
        return np.sqrt(self.omega2)

    def take(self, order: np.ndarray) -> Spectrum:
        """The branches reordered per q: ``order`` shape (Q, p) of branch indices."""
        return Spectrum(self.q, np.take_along_axis(self.omega2, order, axis=1),
                        np.take_along_axis(self.vectors, order[:, None, :], axis=2),
                        np.take_along_axis(self.velocity, order, axis=1))


def fold(q: np.ndarray) -> np.ndarray:
    """q folded into (−π, π] (the bands are 2π-periodic)."""
    f = np.remainder(np.asarray(q, dtype=float), 2 * np.pi)
    return np.where(f > np.pi, f - 2 * np.pi, f)


def spectrum(cell: Cell, q) -> Spectrum:
    """ω², eigenvectors and group velocities at every q, branches ascending at each q.

    Parameters
    ----------
    cell : Cell
    q : array_like, shape (Q,)
        Phases per cell [rad], any real values (the bands are 2π-periodic and even).
    """
    q = np.asarray(q, dtype=float).reshape(-1)
    if not np.all(np.isfinite(q)):
        raise ValueError("spectrum: q must be finite")
    folded = np.where(np.abs(q) <= np.pi, q, fold(q))
    f = factor(cell, np.abs(folded))
    Y, V = jacobi(f.X)
    w2 = np.einsum("qkj,qkj->qj", Y.real, Y.real) + np.einsum("qkj,qkj->qj", Y.imag, Y.imag)
    w2 = np.where(f.zero, 0.0, w2)
    norm = np.sqrt(w2)
    U = Y / np.where(norm > 0, norm, 1.0)[:, None, :]
    vel = np.einsum("qkj,qkj->qj", U.conj(), np.einsum("qkl,qlj->qkj", f.dX, V)).real
    if f.zero.any():
        U, vel = _long_wave(cell, f, U, vel)
    order = np.argsort(w2, axis=1, kind="stable")
    rows = np.arange(q.shape[0])[:, None]
    w2, vel = w2[rows, order], vel[rows, order]
    U = np.take_along_axis(U, order[:, None, :], axis=2)
    neg = folded < 0
    vel = np.where(neg[:, None], -vel, vel)
    U = np.where(neg[:, None, None], U.conj(), U)
    return Spectrum(q, w2, U, vel)


def _long_wave(cell: Cell, f, U: np.ndarray, vel: np.ndarray):
    """Columns that are exactly 0 (q = 0): the translation of their piece, and the sound speed."""
    rm = np.sqrt(cell.masses)
    piece_of = np.empty(cell.p, dtype=np.intp)
    pieces = cell.components()
    for k, (idx, _) in enumerate(pieces):
        piece_of[idx] = k
    for qi, t in zip(*np.nonzero(f.zero)):
        v = int(np.argmax(np.abs(f.dX[qi, :, t])))  # the column's only mass: the piece's last pivot
        idx = pieces[piece_of[v]][0]
        u = np.zeros(cell.p, dtype=complex)
        u[idx] = rm[idx]
        U[qi, :, t] = u / np.linalg.norm(u)
        vel[qi, t] = f.limit[qi, t] / np.sqrt(cell.masses[idx].sum())
    return U, vel


def by_continuity(spec: Spectrum) -> tuple[Spectrum, np.ndarray]:
    """The branches followed along increasing |q| by eigenvector overlap (ascending at the smallest |q|).

    Returns
    -------
    Spectrum
        Reordered.
    order : ndarray of int, shape (Q, p)
        ``order[k, j]``: the ascending index at q_k of branch j.
    """
    from scipy.optimize import linear_sum_assignment

    Q, p = spec.omega2.shape
    order = np.tile(np.arange(p), (Q, 1))
    if Q == 0 or p == 1:
        return spec, order
    seq = np.argsort(np.abs(spec.q), kind="stable")
    w2 = spec.omega2
    scale = np.maximum(np.abs(w2).max(axis=1, keepdims=True), np.finfo(float).tiny)
    gaps = np.diff(w2, axis=1) <= DEGENERATE * scale  # (Q, p-1): neighbours (ascending) that coincide
    ref = spec.vectors[seq[0]].copy()  # reference vector of each branch
    for pos in range(1, Q):
        k = seq[pos]
        U = spec.vectors[k]
        overlap = np.abs(ref.conj().T @ U) ** 2  # [branch, ascending index]
        best = np.argmax(overlap, axis=1)
        if np.unique(best).shape[0] == p and np.all(overlap[np.arange(p), best] > 0.5):
            assign = best
        else:
            assign = linear_sum_assignment(-overlap)[1]
        order[k] = assign
        degenerate = np.zeros(p, dtype=bool)
        degenerate[:-1] |= gaps[k]
        degenerate[1:] |= gaps[k]
        keep = degenerate[assign]  # a branch inside a degenerate cluster keeps its last clear vector
        ref = np.where(keep[None, :], ref, U[:, assign])
    return spec.take(order), order


__all__ = ["DEGENERATE", "Spectrum", "by_continuity", "fold", "spectrum"]
