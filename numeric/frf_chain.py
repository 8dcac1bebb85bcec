"""The receptance of an open chain by dynamic stiffness: O(n) per frequency, relatively accurate.

Every element of an open chain is a two-terminal impedance: the masses and everything tied to
the ground, ``a_i = g_i − ω² m_i + iω c_i`` (wall springs g, ground dashpots c: Rayleigh's α·m
among them), and the element between i−1 and i, ``z_p = k_p + iω c_p`` (spring and dashpots
beside it: Rayleigh's β·k among them). The dynamic stiffness of the part left of a mass, seen
at that mass, is a continued fraction of series and parallel combinations,

    e_0 = a_0,   u_p = z_p + e_{p−1},   e_p = a_p + z_p e_{p−1} / u_p,

and likewise ``f`` from the right end. Then ``X_i = 1 / (e_i + z_{i+1} f_{i+1} / (z_{i+1} + f_{i+1}))``
for the unit force on mass i, and each step away from i multiplies by a transmissibility,
``X_p = X_{p−1} · z_p / (z_p + f_p)`` (to the right) — never a sum of terms of both signs
except ``u`` and ``a`` themselves, whose cancellation is the physics (a resonance of the part
beyond). Each rounding is a relative perturbation of an element (a dynamic stiffness scaled by
1 + δ is that of the same part with every element scaled by 1 + δ), so H is as accurate as
relative changes of the masses, springs and dashpots by O(n ε) allow, whatever their contrast;
the tridiagonal LU of K − ω²M + iωC it replaces loses κ·ε (forming k_{i−1} + k_i rounds a small
spring away next to a large one).

The sweep is compiled with numba (one pass per frequency, O(n) memory, no n × n); a ring (its
closing spring makes a loop) goes through the tridiagonal solve of :mod:`numeric.frf`.
"""

from __future__ import annotations

import functools

import numpy as np

from .array_record import array_record
from .errors import RunRefused


@array_record
class ChainElements:
    """An open chain as impedances: per mass (n,) and per link between p−1 and p (index p, shape (n,); p = 0 unused).

    Attributes
    ----------
    mass, ground_k, ground_c : ndarray, shape (n,)
        Masses, wall springs and ground dashpots at each mass.
    link_k, link_c : ndarray, shape (n,)
        Spring and dashpot constants between masses p−1 and p (entry 0 is 0).
    """

    mass: np.ndarray
    ground_k: np.ndarray
    ground_c: np.ndarray
    link_k: np.ndarray
    link_c: np.ndarray

    @property
    def n(self) -> int:
        return int(self.mass.shape[0])


def _scatter(n: int, ends: np.ndarray, values: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Split elements into ground terms per mass and link terms per position (sums of positive numbers)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    values = np.asarray(values, dtype=float).reshape(-1)
    lo, hi = np.minimum(ends[:, 0], ends[:, 1]), np.maximum(ends[:, 0], ends[:, 1])
    ground = lo < 0
    link = ~ground & (hi - lo == 1)
    if np.any(~ground & ~link & (lo != hi)):
        raise RunRefused(f"frequency response of a chain: its {what} couple masses further apart than "
                         "neighbours (accepted: neighbours, the ground)", quantity="frf")
    g = np.zeros(n)
    np.add.at(g, hi[ground], values[ground])
    z = np.zeros(n)
    np.add.at(z, hi[link], values[link])
    return g, z


def chain_elements(masses: np.ndarray, spring_ends: np.ndarray, stiffness: np.ndarray,
                   damper_ends: np.ndarray | None = None, damping: np.ndarray | None = None) -> ChainElements:
    """The impedances of an open chain from its element lists (walls are -1)."""
    m = np.asarray(masses, dtype=float)
    n = int(m.shape[0])
    gk, zk = _scatter(n, spring_ends, stiffness, "springs")
    if damper_ends is None:
        gc, zc = np.zeros(n), np.zeros(n)
    else:
        gc, zc = _scatter(n, damper_ends, damping, "dashpots")
    return ChainElements(m, gk, gc, zk, zc)


def _receptance_impl(m, gk, gc, zk, zc, omega, i, o, out):
    """H(ω_w) = X_o / F_i for each ω_w (the sweep of the module docstring); out complex (W,)."""
    n = m.shape[0]
    for w in range(omega.shape[0]):
        om = omega[w]
        om2 = om * om
        # left of i (and the transmissibilities towards o < i)
        e = complex(gk[0] - om2 * m[0], om * gc[0])
        prod_left = complex(1.0, 0.0)
        for p in range(1, i + 1):
            z = complex(zk[p], om * zc[p])
            u = z + e
            if p > o:
                prod_left *= z / u
            e = complex(gk[p] - om2 * m[p], om * gc[p]) + z * e / u
        # right of i (and towards o > i)
        t = complex(0.0, 0.0)
        prod_right = complex(1.0, 0.0)
        if i < n - 1:
            f = complex(gk[n - 1] - om2 * m[n - 1], om * gc[n - 1])
            for p in range(n - 1, i, -1):
                z = complex(zk[p], om * zc[p])
                u = z + f
                if p <= o:
                    prod_right *= z / u
                if p - 1 > i:
                    f = complex(gk[p - 1] - om2 * m[p - 1], om * gc[p - 1]) + z * f / u
                else:
                    t = z * f / u
        out[w] = (1.0 / (e + t)) * prod_left * prod_right


@functools.lru_cache(maxsize=1)
def _kernel():
    from .fast_kernels import available

    if available():
        import numba

        return numba.njit(cache=True)(_receptance_impl)
    return _receptance_impl


def chain_receptance(el: ChainElements, omega: np.ndarray, input: int, output: int) -> np.ndarray:
    """``H(iω) = X_output / F_input`` of an open chain, shape (W,), complex (module docstring).

    Parameters
    ----------
    el : ChainElements
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s].
    input, output : int
        Mass indices.
    """
    omega = np.ascontiguousarray(np.asarray(omega, dtype=float).reshape(-1))
    out = np.empty(omega.shape[0], dtype=complex)
    _kernel()(el.mass, el.ground_k, el.ground_c, el.link_k, el.link_c, omega, int(input), int(output), out)
    return out


__all__ = ["ChainElements", "chain_elements", "chain_receptance"]
