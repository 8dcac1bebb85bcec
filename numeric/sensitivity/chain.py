"""Refined modes of an open chain, O(n) per mode: bisection, inverse iteration, Newton in double-double.

1. ω_j by bisection on the Golub–Kahan form of the bidiagonal spring factor
   (:func:`numeric.modes.chain`: relatively accurate, O(n) per value, the values ``modes`` prints);
2. a first shape from the twisted factorisation of ``K − λ_j M`` (stationary qd transforms of the
   subtraction-free ``LDLᵀ`` of K from both ends, :class:`.solvers.ChainSolver`);
3. Newton's correction with double-double residuals from the elements (:func:`.refine.refine_cluster`)
   whose corrector is Nelson's deleted-row system (:class:`.solvers.ChainSolver`): O(n) per step.

An open chain (a Jacobi matrix) has no repeated ω², so every cluster is one mode; the rigid mode of a
free–free chain is the structural translation.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..modes.chain import golub_kahan, spring_positions, bidiagonal_factor
from . import double_double as ddm
from .refine import assemble_refined, refine_cluster, rigid_shape
from .solvers import ChainSolver


def omega_at(f, positions: np.ndarray) -> np.ndarray:
    """ω of the modes at ``positions`` (0-based, ascending, rigid first) by bisection, shape (J,)."""
    s, n = f.size, f.n
    first = s + (s - n)
    t = golub_kahan(f)
    out = np.zeros(len(positions))
    for a, j in enumerate(positions):
        if j < f.rigid:
            continue
        if s == 1:
            out[a] = abs(f.d[0])
            continue
        v = scipy.linalg.eigh_tridiagonal(np.zeros(2 * s), t, eigvals_only=True, select="i",
                                          select_range=(first + j, first + j), lapack_driver="stebz",
                                          tol=np.finfo(float).tiny)
        out[a] = abs(v[0])
    return out


def chain_modes(stencil: ddm.Stencil, ends: np.ndarray, k: np.ndarray, wanted: np.ndarray):
    """Refined modes ``wanted`` (positions, ascending ω²) of an open chain and Nelson's corrector.

    Parameters
    ----------
    stencil : Stencil
    ends : ndarray of int, shape (S, 2)
    k : ndarray, shape (S,)
    wanted : ndarray of int

    Returns
    -------
    RefinedModes, ChainSolver
    """
    masses = stencil.masses
    n = stencil.n
    f = bidiagonal_factor(masses, ends, k)
    solver = ChainSolver(masses, spring_positions(n, ends, k))
    wanted = np.unique(np.asarray(wanted, dtype=np.intp))
    omega = omega_at(f, wanted)
    index, lam, cols, rig, lab, settled = [], [], [], [], [], []
    for j, w in zip(wanted.tolist(), omega.tolist()):
        if j < f.rigid:
            cols.append(rigid_shape(stencil, np.ones(n)))
            index.append(j), lam.append((0.0, 0.0)), rig.append(True), lab.append(0), settled.append(0.0)
            continue
        x, t = solver.vector(w * w)  # the twisted factorisation's vector (x_t = 1)
        q, xs, last = refine_cluster(stencil, k, x[:, None],
                                     lambda rr, lm, tw=t: solver.solve(rr, lm, tw))
        index.append(j), lam.append(q[0]), cols.append(xs[0]), rig.append(False), lab.append(j)
        settled.append(last)
    return assemble_refined(stencil, index, lam, cols, lab, rig, settled), solver


__all__ = ["chain_modes", "omega_at"]
