"""A periodic scene's unit cell as numbers: what the band routes start from.

Read from the generated module through :meth:`springchain.numeric.system.System.band_cell` (the module's
``CELL_*`` constants and ``cell_*`` functions at the parameter values): masses, and springs and dashpots as
``(a, b, reach, constant)`` — from mass ``a`` of cell c to mass ``b`` of cell c + reach, either end -1 for the
ground. Nothing here is formed into K(q) in floating point: :mod:`.factor` eliminates on the elements.
"""

from __future__ import annotations

import numpy as np

from ..io.array_record import array_record


@array_record
class Cell:
    """Masses, springs and dashpots of one cell.

    Attributes
    ----------
    names : tuple of str, shape (p,)
    masses : ndarray, shape (p,)
    ends : ndarray of int, shape (S, 2)
        Spring ends, -1 the ground.
    reach : ndarray of int, shape (S,)
        Cells from the first end to the second.
    stiffness : ndarray, shape (S,)
        Linear stiffness (at the equilibrium) of each spring.
    damper_ends : ndarray of int, shape (D, 2)
    damper_reach : ndarray of int, shape (D,)
    damping : ndarray, shape (D,)
        Dashpot constants.
    rayleigh : (float, float)
        Rayleigh damping C = alpha M + beta K(q) on top of the dashpots ((0, 0) without).
    """

    names: tuple
    masses: np.ndarray
    ends: np.ndarray
    reach: np.ndarray
    stiffness: np.ndarray
    damper_ends: np.ndarray
    damper_reach: np.ndarray
    damping: np.ndarray
    rayleigh: tuple = (0.0, 0.0)

    @property
    def p(self) -> int:
        return int(self.masses.shape[0])

    @property
    def damped(self) -> bool:
        return bool(self.damping.shape[0]) or any(self.rayleigh)

    @property
    def proportional(self) -> bool:
        """Damped by Rayleigh's alpha M + beta K only (closed form per band)."""
        return not self.damping.shape[0]

    @property
    def grounded(self) -> bool:
        """Some spring ties a mass to the ground: no branch reaches 0."""
        return bool((self.ends < 0).any())

    def components(self) -> list[np.ndarray]:
        """The masses of each connected piece of the cell's spring graph (windings ignored), with whether
        the piece is tied to the ground: ``[(indices, grounded), ...]``."""
        parent = list(range(self.p))

        def find(x):
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            return x

        for a, b in self.ends:
            if a >= 0 and b >= 0:
                parent[find(int(a))] = find(int(b))
        grounded = {find(int(a if a >= 0 else b)) for a, b in self.ends if min(a, b) < 0}
        roots = sorted({find(a) for a in range(self.p)})
        return [(np.array([a for a in range(self.p) if find(a) == r], dtype=np.intp), r in grounded) for r in roots]

    @classmethod
    def from_lists(cls, names, masses, springs, stiffness, dampers=(), damping=(), rayleigh=(0.0, 0.0)) -> Cell:
        """From ``springs``/``dampers`` as ``(a, b, reach)`` triples and their constants."""
        s = np.asarray(springs, dtype=np.intp).reshape(-1, 3)
        d = np.asarray(dampers, dtype=np.intp).reshape(-1, 3)
        return cls(tuple(names), np.asarray(masses, dtype=float).reshape(-1), s[:, :2].copy(), s[:, 2].copy(),
                   np.asarray(stiffness, dtype=float).reshape(-1), d[:, :2].copy(), d[:, 2].copy(),
                   np.asarray(damping, dtype=float).reshape(-1), tuple(float(r) for r in rayleigh))


__all__ = ["Cell"]
