"""The Bloch factor X(q) of a cell, D(q) = X Xᴴ, without a subtraction: the band route's first half.

D(q) = M^-1/2 K(q) M^-1/2, where K(q) is the Laplacian of the cell's springs with a phase e^{iqz} on every
spring that reaches z cells on. Forming K(q) in float64 and diagonalising it loses the small branches: their
eigenvalues are below ε·‖D‖ at a large contrast, and the acoustic branch is O(q²) near q = 0. Instead the
masses are eliminated one at a time on the *elements* (:mod:`springchain.derive.bands.elimination` is the same
algorithm in SymPy): the springs between each pair of remaining masses are kept by winding z, springs from a
mass to itself by their winding with weight 4 w sin²(zq/2), springs to the ground apart, so that every pivot

    D_v = Σ w (springs at v) + Σ 4 w sin²(zq/2) (self-springs) + g (ground)

is a sum of positive terms, computed to a few ulps at any contrast, and exactly 0 at q = 0 for the last mass of
a piece with no ground spring. The pivot is the remaining mass with the largest D_v/m_v (diagonal pivoting on
D), so the unit lower triangular factor scaled as M^-1/2 L M^1/2 has entries of size at most 1 and errors of
size ε. The factor

    X = M^-1/2 P L Λ^1/2,   D = X Xᴴ,

then goes to the one-sided Jacobi SVD (:mod:`.jacobi`), whose singular values are accurate to a few ulps in the
relative sense for such a column-scaled, well-conditioned matrix (Demmel–Veselić): ω_j(q) = σ_j, ω²_j = σ_j².

The derivative dX/dq at the same pivot order is carried along (product and quotient rules through every
update), so dω_j/dq = Re(u_jᴴ X' v_j) (Hellmann–Feynman for a singular value: u, v its singular vectors)
needs no division by ω. At q = 0 the last pivot of a free piece is 0 and its column of X' is the long-wave
limit sqrt(K_eff / m_v), K_eff = Σ w z² of its self-springs there (the homogenised stiffness per cell).
Vectorised over q in chunks (memory O(chunk · p² · windings)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..io.array_record import array_record
from .cell import Cell

#: q-points eliminated at once.
CHUNK = 2048


@array_record
class Factor:
    """X(q) and dX/dq of a cell at some q (all ≥ 0), in pivot order.

    Attributes
    ----------
    X, dX : ndarray, shape (Q, p, p), complex
        Rows: masses (the cell's order); columns: pivots.
    zero : ndarray of bool, shape (Q, p)
        Columns that are exactly 0 (q = 0, the last mass of a piece without a ground spring).
    limit : ndarray, shape (Q, p)
        For those columns, the long-wave limit of the branch's group velocity sqrt(K_eff / M_piece) [cells/s].
    """

    X: np.ndarray
    dX: np.ndarray
    zero: np.ndarray
    limit: np.ndarray


@dataclass(frozen=True)
class _Graph:
    """The springs of a cell sorted for the elimination: pair springs by winding, self-springs, ground."""

    p: int
    zmax: int
    W: np.ndarray  # (p, p, 2 zmax + 1): weight of springs a -> b with winding z (index z + zmax)
    L: np.ndarray  # (p, 2 zmax + 1): self-springs of a with winding |z| (index |z|)
    G: np.ndarray  # (p,): springs to the ground

    @classmethod
    def of(cls, cell: Cell) -> _Graph:
        p = cell.p
        a, b, r, k = cell.ends[:, 0], cell.ends[:, 1], cell.reach, cell.stiffness
        pair = (a >= 0) & (b >= 0) & (a != b)
        steps = np.abs(r[pair])
        zmax = int(max(1, min(int(steps.sum()), (p - 1) * int(steps.max(initial=0)))))
        W = np.zeros((p, p, 2 * zmax + 1))
        L = np.zeros((p, 2 * zmax + 1))
        G = np.zeros(p)
        for ai, bi, ri, ki in zip(a.tolist(), b.tolist(), r.tolist(), k.tolist()):
            if ai < 0 or bi < 0:
                G[bi if ai < 0 else ai] += ki
            elif ai == bi:
                if abs(ri) > 2 * zmax:  # a long self-spring of a cell whose pairs are short
                    L = np.pad(L, ((0, 0), (0, abs(ri) - L.shape[1] + 1)))
                L[ai, abs(ri)] += ki
            else:
                W[ai, bi, ri + zmax] += ki
                W[bi, ai, -ri + zmax] += ki
        if L.shape[1] < 2 * zmax + 1:
            L = np.pad(L, ((0, 0), (0, 2 * zmax + 1 - L.shape[1])))
        return cls(p, zmax, W, L, G)


def factor(cell: Cell, q: np.ndarray) -> Factor:
    """X(q), dX/dq for every q in ``q`` (shape (Q,), each ≥ 0)."""
    q = np.asarray(q, dtype=float).reshape(-1)
    if np.any(q < 0):
        raise ValueError("factor: q must be >= 0 (the bands are even in q)")
    graph = _Graph.of(cell)
    parts = [_factor(graph, cell.masses, q[s:s + CHUNK]) for s in range(0, q.shape[0], CHUNK)]
    if not parts:
        p = cell.p
        return Factor(np.zeros((0, p, p), complex), np.zeros((0, p, p), complex), np.zeros((0, p), bool),
                      np.zeros((0, p)))
    return Factor(*(np.concatenate([getattr(f, name) for f in parts]) for name in ("X", "dX", "zero", "limit")))


def _factor(g: _Graph, m: np.ndarray, q: np.ndarray) -> Factor:
    Q, p, zmax = q.shape[0], g.p, g.zmax
    rows = np.arange(Q)
    W = np.broadcast_to(g.W, (Q,) + g.W.shape).copy()
    L = np.broadcast_to(g.L, (Q,) + g.L.shape).copy()
    G = np.broadcast_to(g.G, (Q, p)).copy()
    dW, dL, dG = np.zeros_like(W), np.zeros_like(L), np.zeros_like(G)
    zl = np.arange(L.shape[-1], dtype=float)
    s2 = np.sin(np.outer(q, zl) / 2) ** 2  # sin²(zq/2), (Q, Z)
    ds2 = 0.5 * zl * np.sin(np.outer(q, zl))  # d/dq sin²(zq/2)
    wind = np.arange(-zmax, zmax + 1, dtype=float)
    phase = np.exp(-1j * np.outer(q, wind))  # e^{-izq}, (Q, 2 zmax + 1)
    alive = np.ones((Q, p), dtype=bool)
    off = ~np.eye(p, dtype=bool)
    X = np.zeros((Q, p, p), dtype=complex)
    dX = np.zeros((Q, p, p), dtype=complex)
    zero = np.zeros((Q, p), dtype=bool)
    limit = np.zeros((Q, p))
    rm = np.sqrt(m)
    for t in range(p):
        loops = 4.0 * np.einsum("qaz,qz->qa", L, s2)
        dloops = 4.0 * (np.einsum("qaz,qz->qa", dL, s2) + np.einsum("qaz,qz->qa", L, ds2))
        D = W.sum(axis=(2, 3)) + loops + G
        dD = dW.sum(axis=(2, 3)) + dloops + dG
        v = np.argmax(np.where(alive, D / m, -np.inf), axis=1)
        Dv, dDv = D[rows, v], dD[rows, v]
        Wv, dWv = W[rows, v].copy(), dW[rows, v].copy()  # springs v -> b by winding, (Q, p, Z)
        pos = Dv > 0
        root = np.sqrt(Dv)
        safe = np.where(pos, root, 1.0)
        # the column of X: sqrt(D_v / m_v) at v, -(Σ_z w e^{-izq}) / (sqrt(D_v) sqrt(m_b)) below
        P = np.einsum("qbz,qz->qb", Wv, phase)
        dP = np.einsum("qbz,qz->qb", dWv, phase) - 1j * np.einsum("qbz,z,qz->qb", Wv, wind, phase)
        col = -P / (safe[:, None] * rm[None, :])
        dcol = -dP / (safe[:, None] * rm[None, :]) + P * (dDv / (2 * safe ** 3))[:, None] / rm[None, :]
        col[rows, v] = root / rm[v]
        # d sqrt(D_v / m_v): D'/(2 sqrt(D m)); at D = 0 (q = 0, a free piece's last mass) the long-wave limit
        keff = np.einsum("qz,z->q", L[rows, v], zl ** 2)
        dcol[rows, v] = np.where(pos, dDv / (2 * safe * rm[v]), np.sqrt(keff / m[v]))
        X[:, :, t], dX[:, :, t] = col, dcol
        zero[:, t] = ~pos
        limit[:, t] = np.where(pos, 0.0, np.sqrt(keff))  # sqrt(K_eff); divided by the piece's mass below
        alive[rows, v] = False
        W[rows, v], W[rows, :, v], dW[rows, v], dW[rows, :, v] = 0.0, 0.0, 0.0, 0.0
        if not pos.any():
            continue
        inv = np.where(pos, 1.0 / safe ** 2, 0.0)  # 1 / D_v (0 where D_v = 0: v has no springs left)
        dinv = -dDv * inv * inv
        # v's own self-springs and ground tie each neighbour b to the ground through v: weight w_bv·x/D_v of
        # each, self-springs kept as self-springs of b (their sin²(zq/2) explicit: the long-wave limit reads them)
        tot, dtot = Wv.sum(-1), dWv.sum(-1)
        Lv, dLv, Gv, dGv = L[rows, v].copy(), dL[rows, v].copy(), G[rows, v].copy(), dG[rows, v].copy()
        G += tot * (Gv * inv)[:, None]
        dG += dtot * (Gv * inv)[:, None] + tot * (dGv * inv + Gv * dinv)[:, None]
        L += tot[:, :, None] * (Lv * inv[:, None])[:, None, :]
        dL += (dtot[:, :, None] * (Lv * inv[:, None])[:, None, :]
               + tot[:, :, None] * (dLv * inv[:, None] + Lv * dinv[:, None])[:, None, :])
        present = np.flatnonzero(Wv.any(axis=(0, 1)))
        span = int(present.max() - present.min()) if present.size else 0
        if span > zmax:  # walks longer than any winding so far: widen the winding axes first
            grow = span - zmax
            W, dW = (np.pad(A, ((0, 0), (0, 0), (0, 0), (grow, grow))) for A in (W, dW))
            Wv, dWv = (np.pad(A, ((0, 0), (0, 0), (grow, grow))) for A in (Wv, dWv))
            zmax, present = zmax + grow, present + grow
            wind = np.arange(-zmax, zmax + 1, dtype=float)
            phase = np.exp(-1j * np.outer(q, wind))
        if span >= L.shape[2]:
            L, dL = (np.pad(A, ((0, 0), (0, 0), (0, span - L.shape[2] + 1))) for A in (L, dL))
            zl = np.arange(L.shape[-1], dtype=float)
            s2 = np.sin(np.outer(q, zl) / 2) ** 2
            ds2 = 0.5 * zl * np.sin(np.outer(q, zl))
        for z1 in present:
            for z2 in present:
                a1, a2 = Wv[:, :, z1], Wv[:, :, z2]
                prod = a1[:, :, None] * a2[:, None, :] * inv[:, None, None]
                dprod = ((dWv[:, :, z1][:, :, None] * a2[:, None, :] + a1[:, :, None] * dWv[:, :, z2][:, None, :])
                         * inv[:, None, None] + a1[:, :, None] * a2[:, None, :] * dinv[:, None, None])
                zz = z2 - z1 + zmax  # b -> v -> c: the first spring backwards, then the second
                W[:, :, :, zz] += prod * off
                dW[:, :, :, zz] += dprod * off
                if z1 < z2:  # two springs from b to v with different windings: a self-spring of b
                    L[:, :, z2 - z1] += np.einsum("qbb->qb", prod)
                    dL[:, :, z2 - z1] += np.einsum("qbb->qb", dprod)
    return Factor(X, dX, zero, limit)


__all__ = ["CHUNK", "Factor", "factor"]
