"""Static equilibrium under constant loads, cancellation-free: ``K x = F`` from the spring elements.

Gravity, constant forces and a constant ground acceleration load a scene with a constant force F.
``x = K⁻¹F`` from K formed in float64 is as wrong as κ(K)·ε (a chain hanging from a 1e-9 N/m spring
under 1e9 N/m ones: 180× off in the issue that asked for this); this module never forms K.

The route
---------
K is eliminated in its diagonally dominant parts (the coupling weights ``W_ij = Σ k`` and the wall
stiffness of each mass, as :mod:`numeric.modes.spectrum` does for the modes): eliminating mass p adds
``W_ip W_pj / d_p`` to the couplings and ``W_ip w_p / d_p`` to the wall stiffness, with the pivot
``d_p = w_p + Σ_j W_pj`` a sum of non-negative numbers, so the factor ``K = L D Lᵀ`` has every
entry to a few ulps. Then for a load of one sign the substitutions add non-negative numbers
only (L's off-diagonal entries are ≤ 0): ``y_j += (W_jp / d_p) y_p`` forward, ``x_p = y_p / d_p +
Σ (W_jp / d_p) x_j`` backward. On a chain or any tree of springs, eliminating leaves first, this
is the statics by hand — the spring beyond each mass carries the sum of the loads beyond it,
and stretches by that sum over its k — exactly to rounding. A load of both signs is split into
its positive and negative parts (each entry of each load kept apart, so nothing cancels before
the end), solved separately and subtracted once: ``|x − x_exact| ≤ c·n·ε·K⁻¹|F|`` componentwise,
the best any method can do with loads of both signs. Loops (rings) go through the same
elimination (then fill-in adds non-negative numbers too).

Free pieces (no spring to a wall) have no equilibrium under a net load: such a piece accelerates
as a whole, ``a = ΣF / Σm``, and deforms under the rest of the load, ``F_i − m_i a`` (which sums to
zero over the piece), solved with the last mass of the piece held (the elimination ends there
with an exactly zero pivot); the deformation is defined up to a translation of the piece.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..io.array_record import array_record
from ..modes.spectrum import eliminate, free_pieces, laplacian_parts


@array_record
class Equilibrium:
    """The static response to a constant load.

    Attributes
    ----------
    x : ndarray, shape (N,)
        Static displacement of walled pieces; the deformation of free pieces (last mass of each at 0).
    acceleration : ndarray, shape (N,)
        The uniform acceleration of each free piece (the same value on all its masses; 0 elsewhere).
    """

    x: np.ndarray
    acceleration: np.ndarray


@dataclass(frozen=True)
class _Factor:
    """``K = L D Lᵀ`` in elimination order: pivot masses, their pivots, and the eliminated couplings."""

    order: list
    pivots: list
    couplings: list  # per pivot: (neighbour indices, W_jp / d_p)


def _factor(n: int, ends: np.ndarray, k: np.ndarray) -> _Factor:
    """Subtraction-free elimination of K (leaves and small pieces first: fewest fill-ins)."""
    W, wall = laplacian_parts(n, ends, k)
    alive = np.ones(n, dtype=bool)
    order, pivots, couplings = [], [], []
    for _ in range(n):  # one pivot per step: the loop over masses is the elimination itself
        degree = np.where(alive, (W > 0).sum(axis=1), n + 1)
        d = wall + W.sum(axis=1)
        # eliminate the mass with the fewest live neighbours (a leaf of a tree), a positive pivot first
        score = np.where(alive & (d > 0), degree, 2 * n + 2)
        p = int(np.argmin(score))
        if not score[p] <= n:
            break  # the rest are last masses of free pieces (zero pivots): held
        dp = float(d[p])
        nb, w = eliminate(W, wall, p, dp)
        alive[p] = False
        order.append(p)
        pivots.append(dp)
        couplings.append((nb, w / dp))
    return _Factor(order, pivots, couplings)


def _solve_positive(f: _Factor, load: np.ndarray) -> np.ndarray:
    """``K⁻¹ load`` for a load ≥ 0 (held masses at 0): additions of non-negative numbers only."""
    y = np.array(load, dtype=float)
    for p, (nb, c) in zip(f.order, f.couplings):  # forward: loads carried on to the neighbours
        y[nb] += c * y[p]
    x = np.zeros_like(y)
    for p, dp, (nb, c) in zip(reversed(f.order), reversed(f.pivots), reversed(f.couplings)):  # backward
        x[p] = y[p] / dp + float(np.dot(c, x[nb]))
    return x


def equilibrium(masses: np.ndarray, ends: np.ndarray, k: np.ndarray, loads: list[np.ndarray]) -> Equilibrium:
    """Static displacement (and free pieces' acceleration) under constant loads.

    Parameters
    ----------
    masses, ends, k : ndarray, shapes (N,), (S, 2) of int, (S,)
        The springs, as :func:`.spectrum.spectrum` takes them.
    loads : list of ndarray, shape (N,)
        Constant forces (gravity, constant forces, the ground's constant −m·a_g), kept apart so
        that their positive and negative entries are summed separately.

    Returns
    -------
    Equilibrium
    """
    m = np.asarray(masses, dtype=float)
    n = m.shape[0]
    stack = np.asarray(loads, dtype=float).reshape(-1, n)
    plus = np.sum(np.maximum(stack, 0.0), axis=0)
    minus = np.sum(np.maximum(-stack, 0.0), axis=0)
    acc = np.zeros(n)
    for idx in free_pieces(n, ends):  # a loop over free pieces, not masses
        a = (float(np.sum(plus[idx])) - float(np.sum(minus[idx]))) / float(np.sum(m[idx]))
        acc[idx] = a
        share = m[idx] * a  # the inertial part of the load moves the piece; the rest deforms it
        plus[idx] += np.maximum(-share, 0.0)
        minus[idx] += np.maximum(share, 0.0)
    f = _factor(n, ends, k)
    x = _solve_positive(f, plus) - _solve_positive(f, minus)
    return Equilibrium(x, acc)


__all__ = ["Equilibrium", "equilibrium"]
