"""The modes of a finite periodic chain, each named by its band and wavenumber, or as a gap mode.

The finite chain's modes come from the accurate spectrum of its own masses and springs
(:attr:`springchain.numeric.system.System.spectrum`: the spring-factor SVD). Mass i lies in cell i // p at
place i % p of the cell. A mode at ω² is

* a **band mode** (band j = the j-th lowest branch at each q, wavenumber q ∈ [0, π]) when some band reaches
  ω²: q solves ω²_j(q) = ω² (safeguarded Newton on the accurate branch with its group velocity); where several
  (j, q) do, the one whose Bloch waves e^{±iqc} U_j(±q) carry most of the mode's weight (its projection);
* a **gap mode** otherwise: it decays by e^{−κ} per cell, κ = Im q(ω) (:mod:`.decay`), localisation length
  1/κ cells; an **edge** mode when its largest cell is at an open end (within :data:`EDGE_CELLS` cells), a
  **defect** mode otherwise (a cell that differs, or a ring).

In a ring of N cells every band mode has q = 2πs/N (its ω² is ω²_j(2πs/N)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cell import Cell
from .decay import attenuation
from .spectrum import spectrum

#: A gap mode whose largest cell is at most this many cells from an open end is an edge mode.
EDGE_CELLS = 2


@dataclass(frozen=True)
class FiniteMode:
    """One mode of the finite chain."""

    omega2: float
    band: int | None
    q: float | None
    kind: str  # "band", "edge" or "defect"
    localisation: float | None = None  # cells (gap modes)
    weight: float | None = None  # fraction of the mode's weight on the Bloch waves (band modes)

    @property
    def omega(self) -> float:
        return float(np.sqrt(max(self.omega2, 0.0)))

    def as_json(self) -> dict:
        return {"omega2": self.omega2, "omega": self.omega, "band": self.band, "q": self.q, "kind": self.kind,
                "localisation_length": self.localisation, "bloch_weight": self.weight}


def _solve(cell: Cell, j: int, a: float, b: float, target: np.ndarray) -> np.ndarray:
    """q in [a, b] with ω_j(q) = target (ω_j monotone there): :func:`.dos.newton`."""
    from .dos import newton

    wa, wb = spectrum(cell, np.array([a, b])).omega[:, j]
    return newton(cell, j, a, b, wa, wb, target)


def _weight(cell: Cell, psi: np.ndarray, j: int, q: float) -> float:
    """Fraction of the mode (mass-weighted, shape (cells, p)) on the Bloch waves of band j at ±q."""
    u = spectrum(cell, np.array([q])).vectors[0, :, j]
    c = np.arange(psi.shape[0])
    total = float(np.sum(np.abs(psi) ** 2))
    if total == 0:
        return 0.0
    amp = [abs(np.sum((psi @ (u if s > 0 else u.conj()).conj()) * np.exp(-1j * s * q * c))) ** 2 for s in (1, -1)]
    return float(sum(amp) / (total * psi.shape[0]))


def label(cell: Cell, omega2: np.ndarray, vectors: np.ndarray, ring: bool) -> list[FiniteMode]:
    """Band and q, or gap kind and localisation length, of every mode.

    Parameters
    ----------
    omega2 : ndarray, shape (N,)
    vectors : ndarray, shape (N, N)
        Mass-weighted unit mode vectors as columns (M^1/2 φ).
    ring : bool
        The chain closes on itself (no ends: a gap mode is a defect mode).
    """
    from .dos import SAMPLES, _pieces

    p, n = cell.p, omega2.shape[0]
    cells = -(-n // p)
    omega = np.sqrt(np.maximum(omega2, 0.0))
    qs = np.linspace(0.0, np.pi, SAMPLES)
    grid = spectrum(cell, qs)
    candidates: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for j in range(p):
        for a, b in _pieces(cell, j, qs, grid.omega[:, j]):
            ends = spectrum(cell, np.array([a, b])).omega[:, j]
            lo, hi = min(ends), max(ends)
            tol = 1e-12 * max(hi, 1e-300)
            inside = np.flatnonzero((omega >= lo - tol) & (omega <= hi + tol))
            if inside.size:
                for k, q in zip(inside, _solve(cell, j, a, b, np.clip(omega[inside], lo, hi))):
                    candidates[k].append((j, float(q)))
    out: list[FiniteMode | None] = [None] * n
    gap = [k for k in range(n) if not candidates[k]]
    for k in range(n):
        if not candidates[k]:
            continue
        psi = np.zeros(cells * p, dtype=complex)
        psi[:n] = vectors[:, k]
        psi = psi.reshape(cells, p)
        scored = [(_weight(cell, psi, j, q) if len(candidates[k]) > 1 else None, j, q) for j, q in candidates[k]]
        w, j, q = max(scored, key=lambda t: -1.0 if t[0] is None else t[0])
        out[k] = FiniteMode(float(omega2[k]), j, q, "band", None, w)
    if gap:
        kappa, _ = attenuation(cell, omega[gap])
        for k, kap in zip(gap, kappa):
            weight = np.abs(np.pad(vectors[:, k], (0, cells * p - n))).reshape(cells, p) ** 2
            peak = int(np.argmax(weight.sum(axis=1)))
            length = float(1.0 / kap) if kap > 0 else None
            edge = not ring and min(peak, cells - 1 - peak) <= EDGE_CELLS
            out[k] = FiniteMode(float(omega2[k]), None, None, "edge" if edge else "defect", length)
    return out


__all__ = ["FiniteMode", "label"]
