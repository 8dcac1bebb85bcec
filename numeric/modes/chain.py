"""Modes of an open chain (free or wall ends) from its bidiagonal spring factor.

``D = M^-1/2 K M^-1/2 = GᵀG`` with ``G = diag(√k) B M^-1/2`` (B the spring incidence); for an
open chain G is bidiagonal, one row per spring in chain order. A bidiagonal factor determines
its singular values ω_j to high *relative* accuracy, whatever the contrast of masses and springs,
and two LAPACK routes keep that accuracy:

* **values** by bisection on the Golub–Kahan form (the 2s × 2s tridiagonal with zero diagonal
  and off-diagonals d₀, e₀, d₁, …; LAPACK ``stebz`` with a tolerance below underflow): O(s) per
  value, so any selection (the 10 lowest and 10 highest of 2·10⁵) costs O(s) each — the route
  of the generated module's ``omega2()``, and the same numbers;
* **vectors** by LAPACK's bidiagonal QR ``dbdsqr`` (:mod:`numeric.modes.lapack_bidiagonal`), whose
  errors are bounded by ε over the relative gap; O(s³) (n = 2000: about 8 s).

Forming D and calling ``eigh_tridiagonal`` (the route this replaces for the exact method)
loses ~κ(D)·ε on the small ω² and mixes the low modes: 2.6e-5 of the amplitude at t = 10⁴ on a
57-mass chain with masses 1/1e6 and springs 1/1e4.

G is built with non-negative entries (row p: √k_p/√m_{p−1} and √k_p/√m_p); the true factor
differs by the column signs ``(−1)^i`` (and row signs, which GᵀG does not see), so the modes of
D are ``(−1)^i`` times the singular vectors. A free–free chain has n − 1 rows and a wall–wall
chain n + 1; the first gets a zero row, the second a zero column, so that G is square: the zero
row adds nothing (its zero singular value is the rigid mode), the zero column adds one zero
singular value that is dropped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..errors import RunRefused
from .lapack_bidiagonal import bidiagonal_svd

#: Largest ratio of the spring factor's entries that bisection (stebz, which squares them) resolves in
#: the relative sense; beyond it the values come from LAPACK's dbdsqr QR (O(n²)), up to QR_MAX masses.
STEBZ_RANGE = 1e140
QR_MAX = 4000


@dataclass(frozen=True)
class Bidiagonal:
    """The square bidiagonal spring factor of an open chain.

    Attributes
    ----------
    d : ndarray, shape (s,)
        Diagonal (non-negative).
    e : ndarray, shape (s − 1,)
        Off-diagonal (``G[i+1, i]`` if lower, ``G[i, i+1]`` if upper; non-negative).
    upper : bool
    n : int
        Masses; ``s = n + 1`` for a wall–wall chain (padded column), else ``s = n``.
    rigid : int
        1 for a free–free chain (its zero singular value is the rigid mode), else 0.
    """

    d: np.ndarray = field(repr=False)
    e: np.ndarray = field(repr=False)
    upper: bool
    n: int
    rigid: int

    @property
    def size(self) -> int:
        return int(self.d.shape[0])

    @property
    def padded_column(self) -> bool:
        """A wall–wall chain: one more singular value (0) than modes."""
        return self.size == self.n + 1


def spring_positions(n: int, ends: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Stiffness at chain positions 0 … n: 0 the left wall, p the spring between p−1 and p, n the right wall.

    Parallel springs add (a sum of positive numbers). Raises ValueError if the springs are not an
    open chain 0 – 1 – … – n−1 (with optional walls at its ends).
    """
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    k = np.asarray(k, dtype=float)
    lo, hi = np.minimum(ends[:, 0], ends[:, 1]), np.maximum(ends[:, 0], ends[:, 1])
    wall = lo < 0
    inner = ~wall & (hi - lo == 1)
    pos = np.full(ends.shape[0], -1, dtype=np.intp)
    pos[inner] = hi[inner]
    if n >= 2:
        pos[wall & (hi == 0)] = 0
        pos[wall & (hi == n - 1)] = n
    elif n == 1:
        pos[wall & (hi == 0)] = 0  # one mass: every wall spring acts on it alike
    if np.any(pos < 0):
        raise ValueError("not an open chain: a spring joins masses that are not neighbours (or a ring)")
    stiff = np.zeros(n + 1)
    np.add.at(stiff, pos, k)
    if n >= 2 and np.any(stiff[1:n] <= 0):
        raise ValueError("not an open chain: a neighbour spring is missing")
    return stiff


def bidiagonal_factor(masses: np.ndarray, ends: np.ndarray, k: np.ndarray) -> Bidiagonal:
    """The square bidiagonal spring factor of an open chain (see the module docstring).

    Parameters
    ----------
    masses, ends, k : ndarray, shapes (n,), (S, 2) of int, (S,)
        The springs of an open chain, as :func:`.spectrum.spectrum` takes them.
    """
    m = np.asarray(masses, dtype=float)
    n = int(m.shape[0])
    stiff = spring_positions(n, ends, k)
    rk, rm = np.sqrt(stiff), 1.0 / np.sqrt(m)
    left, right = stiff[0] > 0, stiff[n] > 0
    if n == 1:
        return Bidiagonal(np.array([np.sqrt(stiff[0] + stiff[1]) * rm[0]]), np.zeros(0), True, 1,
                          0 if (left or right) else 1)
    if left:  # rows: left wall, then spring p between p−1 and p: lower bidiagonal
        d = rk[:n] * rm
        e = rk[1:n] * rm[:n - 1]
        if right:  # the right wall's row: a zero column makes it square
            d, e = np.append(d, 0.0), np.append(e, rk[n] * rm[n - 1])
        return Bidiagonal(d, e, False, n, 0)
    d = np.append(rk[1:n] * rm[:n - 1], rk[n] * rm[n - 1] if right else 0.0)  # rows: springs, then wall or 0
    e = rk[1:n] * rm[1:]
    return Bidiagonal(d, e, True, n, 0 if right else 1)


def golub_kahan(f: Bidiagonal) -> np.ndarray:
    t = np.empty(2 * f.size - 1)
    t[0::2], t[1::2] = f.d, f.e
    return t


def singular_values(f: Bidiagonal, lowest: int | None = None, highest: int = 0) -> np.ndarray:
    """ω (ascending) by bisection on the Golub–Kahan form: all n, or the ``lowest`` and ``highest``.

    The rigid mode of a free–free chain is exactly 0. O(s) per value.

    Returns
    -------
    ndarray, shape (n,) or (lowest + highest,)
        Every ω, or the ``lowest`` smallest then the ``highest`` largest (overlaps removed).
    """
    s, n = f.size, f.n
    first = s + (s - n)  # Golub–Kahan index of the smallest physical ω (the padding zero skipped)
    t = golub_kahan(f)
    # stebz floors its pivots and its stopping tolerance at tiny * max(1, max entry²) (absolute): at
    # entries of 1e149 that is 2e-10, which took ω² = 2 to 1.99999999768. Scaled by a power of 2 (exact)
    # to a largest entry in [1/2, 1), the floor is tiny itself: relative accuracy down to ω ~ 1e-300.
    scale = np.ldexp(1.0, -int(np.frexp(np.max(t))[1])) if t.size and np.max(t) > 0 else 1.0
    nonzero = t[t > 0]
    if nonzero.size > 1 and np.max(nonzero) > STEBZ_RANGE * np.min(nonzero):
        # stebz squares the entries: past STEBZ_RANGE the small ones underflow (every ω² of a 14-mass
        # chain of 1/3e149 kg and 1e80/1e-80 N/m came out as 3.2e-230, true 6.3e-231 ... 1.2e-229)
        if s > QR_MAX:
            raise RunRefused(f"the spring factor's entries sqrt(k/m) span {np.max(nonzero) / np.min(nonzero):.3g} "
                             f"(more than {STEBZ_RANGE:g}) in a chain of {n} masses: float64 bisection cannot give "
                             f"its ω relative accuracy, and the O(n²) QR route takes at most {QR_MAX} masses",
                             "masses")
        # dbdsqr's zero-shift QR: relatively accurate, no squares (its dqds, without vectors, lost 4e-4 here)
        sigma, _ = bidiagonal_svd(f.d, f.e, f.upper, vectors=False, qr=True)
        sigma = np.sort(sigma)[s - n:]
        sigma[: f.rigid] = 0.0
        if lowest is None or lowest + highest >= n:
            return sigma
        return np.concatenate([sigma[:lowest], sigma[n - highest:]])

    def select(a: int, b: int) -> np.ndarray:
        if b < a:
            return np.zeros(0)
        if s == 1:
            return np.abs(f.d[:1])
        v = scipy.linalg.eigh_tridiagonal(np.zeros(2 * s), t * scale, eigvals_only=True, select="i",
                                          select_range=(a, b), lapack_driver="stebz", tol=np.finfo(float).tiny)
        return np.sort(np.abs(v)) / scale

    if lowest is None or lowest + highest >= n:
        w = select(first, 2 * s - 1)
        w[: f.rigid] = 0.0
        return w
    low = select(first, first + lowest - 1)
    low[: f.rigid] = 0.0
    return np.concatenate([low, select(2 * s - highest, 2 * s - 1)])


@dataclass(frozen=True)
class ChainSpectrum:
    """Modes of an open chain.

    Attributes
    ----------
    omega : ndarray, shape (n,)
        Ascending, the rigid mode (free–free) exactly 0; bisection values (:func:`singular_values`).
    vectors : ndarray, shape (n, n)
        Mass-weighted orthonormal modes (eigenvectors of D) as columns, in ``omega`` order.
    masses : ndarray, shape (n,)
    rigid : int
    """

    omega: np.ndarray = field(repr=False)
    vectors: np.ndarray = field(repr=False)
    masses: np.ndarray = field(repr=False)
    rigid: int


def chain_spectrum(masses: np.ndarray, ends: np.ndarray, k: np.ndarray) -> ChainSpectrum:
    """ω and mass-weighted modes of an open chain, both relatively accurate (module docstring).

    The rigid mode of a free–free chain is the structural one (``√m/‖√m‖``, ω = 0 exactly) and
    the elastic modes are made orthogonal to it (one Löwdin step, as :mod:`numeric.modes.spectrum`).
    """
    m = np.asarray(masses, dtype=float)
    f = bidiagonal_factor(m, ends, k)
    n = f.n
    omega = singular_values(f)
    sigma, V = bidiagonal_svd(f.d, f.e, f.upper)
    V = V[:n, :n][:, ::-1]  # ascending; a padded column's zero singular value is the last (dropped)
    V = V * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)[:, None]  # the column signs of the true factor
    if f.rigid:
        r = np.sqrt(m) / np.linalg.norm(np.sqrt(m))
        V[:, 0] = r
        el = V[:, 1:] - r[:, None] * (r @ V[:, 1:])[None, :]
        el = el - 0.5 * (el @ (el.T @ el - np.eye(n - 1)))
        V[:, 1:] = el
    big = np.argmax(np.abs(V), axis=0)  # a deterministic sign: the largest component positive
    V = V * np.where(V[big, np.arange(n)] < 0, -1.0, 1.0)[None, :]
    return ChainSpectrum(omega, V, m, f.rigid)


__all__ = ["Bidiagonal", "bidiagonal_factor", "singular_values", "ChainSpectrum", "chain_spectrum"]


def extreme_omega2(masses: np.ndarray, ends: np.ndarray, k: np.ndarray, each_end: int) -> dict[int, float]:
    """``{position: ω²}`` of the ``each_end`` lowest and highest modes of an open chain, by bisection on the
    bidiagonal spring factor (O(n) per value): what ``modes`` lists of a chain too long to list whole.

    Parameters
    ----------
    masses : ndarray, shape (n,)
    ends : ndarray of int, shape (S, 2)
        Spring ends, -1 a wall.
    k : ndarray, shape (S,)
    each_end : int
        How many modes at each end of the spectrum.
    """
    n = masses.shape[0]
    w = singular_values(bidiagonal_factor(masses, ends, k), each_end, each_end)
    return dict(zip(list(range(each_end)) + list(range(n - each_end, n)), (w * w).tolist()))
