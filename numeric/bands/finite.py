"""The modes of a finite periodic chain, each named by its band and wavenumber, or as a gap mode.

The finite chain's modes come from the accurate spectrum of its own masses and springs
(:attr:`springchain.numeric.system.System.spectrum`: the spring-factor SVD). Mass i lies in cell i // p at
place i % p of the cell. A mode at ω² is

* a **band mode** (band j = the j-th lowest branch at each q, wavenumber q ∈ [0, π]) when some band reaches
  ω²: q solves ω²_j(q) = ω² (safeguarded Newton on the accurate branch with its group velocity); where several
  (j, q) do, the one whose Bloch waves e^{±iqc} U_j(±q) carry most of the mode's weight (its projection), that
  fraction given for every band mode (``bloch_weight``);
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
    #: Band modes: the fraction of the mode (mass-weighted) in the span of its band's Bloch waves at ±q (1 for a
    #: ring's mode, near 1 for an open chain's standing wave); None for gap modes.
    weight: float | None = None

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


def _weight(psi: np.ndarray, u: np.ndarray, q: float) -> float:
    """Fraction of the mode (mass-weighted, shape (cells, p)) in the span of the Bloch waves e^{±iqc} of the cell
    vector ``u`` (p,) at ±q over the chain's cells: the squared norm of its orthogonal projection there, over its
    own (in [0, 1]; at q = 0 or π the two waves are one, and near them nearly parallel: their span counts once)."""
    total = float(np.sum(np.abs(psi) ** 2))
    if total == 0:
        return 0.0
    phase = np.exp(1j * q * np.arange(psi.shape[0]))[:, None]
    waves = np.stack([(phase * u[None, :]).ravel(), (phase.conj() * u.conj()[None, :]).ravel()], axis=1)
    basis, r, _ = np.linalg.svd(waves, full_matrices=False)
    basis = basis[:, r > 1e-8 * r[0]]
    return float(min(np.sum(np.abs(basis.conj().T @ psi.ravel()) ** 2) / total, 1.0))


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
    from .dos import SAMPLES, band_pieces

    p, n = cell.p, omega2.shape[0]
    cells = -(-n // p)
    omega = np.sqrt(np.maximum(omega2, 0.0))
    qs = np.linspace(0.0, np.pi, SAMPLES)
    grid = spectrum(cell, qs)
    candidates: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for j in range(p):
        for a, b in band_pieces(cell, j, qs, grid.omega[:, j]):
            ends = spectrum(cell, np.array([a, b])).omega[:, j]
            lo, hi = min(ends), max(ends)
            tol = 1e-12 * max(hi, 1e-300)
            inside = np.flatnonzero((omega >= lo - tol) & (omega <= hi + tol))
            if inside.size:
                for k, q in zip(inside, _solve(cell, j, a, b, np.clip(omega[inside], lo, hi))):
                    candidates[k].append((j, float(q)))
    out: list[FiniteMode | None] = [None] * n
    gap = [k for k in range(n) if not candidates[k]]
    flat = [(k, j, q) for k in range(n) for j, q in candidates[k]]
    bloch = spectrum(cell, np.array([q for _, _, q in flat])).vectors if flat else None  # (C, p, p), one call
    best: dict[int, tuple[float, int, float]] = {}
    for c, (k, j, q) in enumerate(flat):
        psi = np.zeros(cells * p, dtype=complex)
        psi[:n] = vectors[:, k]
        w = _weight(psi.reshape(cells, p), bloch[c, :, j], q)
        if k not in best or w > best[k][0]:
            best[k] = (w, j, q)
    for k, (w, j, q) in best.items():
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
