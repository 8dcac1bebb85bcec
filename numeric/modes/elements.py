"""A linear scene as element lists — the numbers the accurate routes start from.

Forming K, C or K − ω²M + iωC in float64 adds a small spring to a large one and rounds it away;
the routes of :mod:`numeric.frf.dense`, :mod:`numeric.frf.chain`, :mod:`numeric.exact.equilibrium` and
:mod:`numeric.modal_forced` read the elements instead: masses, springs (ends, k), dashpots
(ends, c), the Rayleigh coefficients (α, β) and modal damping ratios, each exactly as the
generated module computes it from the parameters. Chain modules list Rayleigh damping among
their dashpots (α·m to the ground, β·k beside each spring), so ``rayleigh`` is None for them.
"""

from __future__ import annotations

from dataclasses import field

import numpy as np

from ..io.array_record import array_record
from ..system import System


@array_record
class Elements:
    """Masses, springs, dashpots and damping models of a linear scene.

    Attributes
    ----------
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices, -1 for a wall.
    stiffness : ndarray, shape (S,)
    damper_ends : ndarray of int, shape (D, 2)
    damping : ndarray, shape (D,)
    rayleigh : (float, float) or None
        C gets α·M + β·K.
    modal_zeta : ndarray, shape (N,) or None
        Modal damping ratios in ascending ω (rigid modes included).
    """

    masses: np.ndarray
    spring_ends: np.ndarray
    stiffness: np.ndarray
    damper_ends: np.ndarray
    damping: np.ndarray
    rayleigh: tuple | None = None
    modal_zeta: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def from_system(cls, system: System) -> "Elements":
        ends, c = system.dampers()
        rayleigh = modal = None
        if not system.chain:  # [damping] models are read for [masses] scenes (chains: dashpots only)
            rayleigh, modal = system.rayleigh_coefficients(), system.modal_damping_ratios()
        return cls(system.masses, system.spring_ends, system.stiffness, ends, c, rayleigh, modal)

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    @property
    def damped(self) -> bool:
        return bool(self.damping.shape[0]) or self.rayleigh is not None or self.modal_zeta is not None

    @property
    def proportional(self) -> bool:
        """Damping diagonal in the undamped modes by construction (no dashpots)."""
        return not self.damping.shape[0]


def incidence(n: int, ends: np.ndarray) -> np.ndarray:
    """Element–mass incidence B, shape (E, N): +1 at end a, −1 at end b (walls omitted)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    B = np.zeros((ends.shape[0], n))
    rows = np.arange(ends.shape[0])
    for col, sign in ((0, 1.0), (1, -1.0)):
        on = ends[:, col] >= 0
        np.add.at(B, (rows[on], ends[on, col]), sign)
    return B


def modal_damping(el: Elements, omega: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """``G = Φᵀ C Φ`` in the M-orthonormal undamped modes, shape (N, N).

    Dashpots as ``(BΦ)ᵀ diag(c) (BΦ)``; Rayleigh ``α I + β diag(ω²)`` and modal damping
    ``diag(2 ζ_j ω_j)`` exactly diagonal (their definition in these coordinates).

    Parameters
    ----------
    omega : ndarray, shape (N,)
    shapes : ndarray, shape (N, N)
        Physical M-orthonormal mode shapes as columns, in ``omega`` order.
    """
    n = el.n
    G = np.zeros((n, n))
    if el.damping.shape[0]:
        P = incidence(n, el.damper_ends) @ shapes
        G += P.T @ (el.damping[:, None] * P)
        G = 0.5 * (G + G.T)
    diag = np.zeros(n)
    if el.rayleigh is not None:
        diag += el.rayleigh[0] + el.rayleigh[1] * omega * omega
    if el.modal_zeta is not None:
        diag += 2.0 * el.modal_zeta * omega
    return G + np.diag(diag)


__all__ = ["Elements", "incidence", "modal_damping"]
