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

from ..io.array_record import array_record
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


def _match(ref: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The ascending index at a new q of each branch whose last vector is a column of ``ref`` (max overlap)."""
    from scipy.optimize import linear_sum_assignment

    overlap = np.abs(ref.conj().T @ U) ** 2  # [branch, ascending index]
    best = np.argmax(overlap, axis=1)
    if np.unique(best).shape[0] == best.shape[0] and np.all(overlap[np.arange(best.shape[0]), best] > 0.5):
        return best
    return linear_sum_assignment(-overlap)[1]


#: Bisections of a step where branches change places (a crossing or a sharp avoided one).
MAX_DEPTH = 52


def _step(cell: Cell, qa: float, qb: float, ref: np.ndarray, rank: np.ndarray, Ub: np.ndarray, depth: int):
    """Follow the branches from qa (vectors ``ref``, ascending indices ``rank``) to qb (vectors ``Ub``).

    Where the branches' ascending order changes over the step, it is bisected until each piece either keeps the
    order (the eigenvectors turned gradually: an avoided crossing, the order kept) or is too short to turn in
    (a true crossing: the vectors pass through each other unchanged, the order swaps)."""
    assign = _match(ref, Ub)
    if np.array_equal(assign, rank) or depth == 0 or abs(qb - qa) <= 1e-13 * max(1.0, abs(qb)):
        return assign
    mid = 0.5 * (qa + qb)
    Um = spectrum(cell, np.array([mid])).vectors[0]
    left = _step(cell, qa, mid, ref, rank, Um, depth - 1)
    return _step(cell, mid, qb, Um[:, left], left, Ub, depth - 1)


def by_continuity(spec: Spectrum, cell: Cell | None = None) -> tuple[Spectrum, np.ndarray]:
    """The branches followed along increasing |q| by eigenvector overlap (ascending at the smallest |q|).

    With ``cell``, a step where two branches change places is bisected (:func:`_step`): a sharp avoided
    crossing keeps the branches apart, a true crossing lets them pass — whatever the grid's spacing.

    Returns
    -------
    Spectrum
        Reordered.
    order : ndarray of int, shape (Q, p)
        ``order[k, j]``: the ascending index at q_k of branch j.
    """
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
        k, prev = seq[pos], seq[pos - 1]
        U = spec.vectors[k]
        if cell is None:
            assign = _match(ref, U)
        else:
            assign = _step(cell, abs(float(spec.q[prev])), abs(float(spec.q[k])), ref, order[prev], U, MAX_DEPTH)
        order[k] = assign
        degenerate = np.zeros(p, dtype=bool)
        degenerate[:-1] |= gaps[k]
        degenerate[1:] |= gaps[k]
        keep = degenerate[assign]  # a branch inside a degenerate cluster keeps its last clear vector
        ref = np.where(keep[None, :], ref, U[:, assign])
    return spec.take(order), order


def align(grid: Spectrum, spec: Spectrum, cell: Cell) -> Spectrum:
    """``spec``'s branches in the continuity order of ``grid`` (a fine grid on [0, π] ordered by
    :func:`by_continuity`): each q is reached from the grid point nearest its folded |q| by :func:`_step` (a
    coarse or unsorted set of q cannot be followed by itself: eigenvectors turn between samples)."""
    Q, p = spec.omega2.shape
    if Q == 0 or p == 1:
        return spec
    folded = fold(spec.q)
    near = np.abs(np.abs(folded)[:, None] - grid.q[None, :]).argmin(axis=1)
    mine = np.where((folded < 0)[:, None, None], spec.vectors.conj(), spec.vectors)
    rank = np.argsort(np.argsort(grid.omega2, axis=1, kind="stable"), axis=1, kind="stable")[near]
    overlap = np.abs(np.einsum("qkb,qkj->qbj", grid.vectors[near].conj(), mine)) ** 2  # [q, branch, ascending]
    order = overlap.argmax(axis=2)
    clear = (order == rank).all(axis=1) & (overlap.max(axis=2) > 0.5).all(axis=1)
    for k in np.flatnonzero(~clear):
        g = near[k]
        order[k] = _step(cell, float(grid.q[g]), abs(float(folded[k])), grid.vectors[g], rank[k], mine[k], MAX_DEPTH)
    return spec.take(order)


__all__ = ["DEGENERATE", "Spectrum", "align", "by_continuity", "fold", "spectrum"]
