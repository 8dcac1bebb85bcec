"""Determinants of a cell's Bloch stiffness K(q) without a subtraction: the symbolic form.

K(q) is the Laplacian of the cell's spring graph with a phase e^{iqz} on every spring that reaches z cells on
(a *connection* Laplacian). Eliminating one mass at a time keeps that form: the Schur complement is again such
a Laplacian, on springs whose weights are products and quotients of the old ones, with windings that add, and
the pair of springs a mass had to the same neighbour with different windings turns into a spring from that
neighbour to itself weighted by 4 sin²(Δz q/2). Every pivot is then a sum of positive terms,

    D_v = Σ springs at v + Σ 4 w sin²(z q/2) (self-springs) + ground springs,

and det K = Π D_v (Kenyon's matrix-tree theorem for connection Laplacians says the same: a sum over
cycle-rooted spanning forests). The coefficients of the characteristic polynomial
det(K − λM) = Σ_j c_j (−λ)^j are sums of such determinants, c_j = Σ_{|R| = j} Π_{a∈R} m_a · det K_(removed R),
so each is a sum of positive terms too: no cancellation at any contrast, and c_0(0) = 0 exactly without a spring
to the ground. :mod:`springchain.numeric.bands.factor` runs the same elimination in floating point.
"""

from __future__ import annotations

from collections import defaultdict
from itertools import combinations

import sympy as sp

from .cell import GROUND


def sin2(z: int, q: sp.Symbol) -> sp.Expr:
    """sin²(z q / 2) (z > 0)."""
    return sp.sin(z * q / 2) ** 2


def determinant(p: int, springs, q: sp.Symbol, removed=frozenset()) -> sp.Expr:
    """det of K(q) with the masses ``removed`` held fixed, as a sum of positive terms (nested).

    Parameters
    ----------
    p : int
        Masses in the cell.
    springs : iterable of (a, b, reach, k)
        Either end -1 for the ground.
    removed : set of int
        Masses held fixed (their rows and columns struck out).
    """
    W = defaultdict(lambda: sp.Integer(0))  # (a, b, z): weight of springs a -> b with phase e^{izq}
    L = defaultdict(lambda: sp.Integer(0))  # (a, z > 0): self-springs, 4 w sin²(zq/2) on the diagonal
    G = defaultdict(lambda: sp.Integer(0))  # a: springs to the ground (or to a fixed mass)
    for a, b, z, k in springs:
        fixed_a, fixed_b = a == GROUND or a in removed, b == GROUND or b in removed
        if fixed_a and fixed_b:
            continue
        if fixed_a or fixed_b:
            G[b if fixed_a else a] += k
        elif a == b:
            L[a, abs(z)] += k
        else:
            W[a, b, z] += k
            W[b, a, -z] += k
    alive = [v for v in range(p) if v not in removed]
    det = sp.Integer(1)
    while alive:
        v = alive.pop()
        edges = [(b, z, w) for (a, b, z), w in W.items() if a == v and b in alive and w != 0]
        loops = sp.Add(*[4 * w * sin2(z, q) for (a, z), w in L.items() if a == v and w != 0])
        d = sp.Add(*[w for _, _, w in edges]) + loops + G[v]
        det *= d
        if d == 0:
            return sp.Integer(0)
        rest = loops + G[v]
        for b, z, w in edges:  # the rest of v's weight ties b to the ground through v
            if rest != 0:
                G[b] += w * rest / d
        for (b, z1, w1), (c, z2, w2) in combinations(edges, 2):
            if b == c:
                if z1 != z2:  # two springs from b to v with different windings: a self-spring of b
                    L[b, abs(z1 - z2)] += w1 * w2 / d
            else:  # b -> v -> c: the first spring walked backwards, then the second
                W[b, c, z2 - z1] += w1 * w2 / d
                W[c, b, z1 - z2] += w1 * w2 / d
        for key in [key for key in W if v in key[:2]]:
            del W[key]
    return det


def coefficients(masses, springs, q: sp.Symbol) -> list[sp.Expr]:
    """c_0 ... c_p of det(K(q) − λM) = Σ_j c_j (−λ)^j, each a sum of positive terms."""
    p = len(masses)
    out = []
    for j in range(p + 1):
        terms = [sp.Mul(*[masses[a] for a in R]) * determinant(p, springs, q, frozenset(R))
                 for R in combinations(range(p), j)]
        out.append(sp.Add(*terms))
    return out


__all__ = ["coefficients", "determinant", "sin2"]
