"""Band edges, extrema and gaps of a cell.

Each branch (followed by continuity, :func:`.spectrum.by_continuity`) is sampled on q ∈ [0, π] (the bands are
even); its lowest and highest values are the sampled ends q = 0, π or interior extrema, each refined by a
bounded scalar search on the accurate ω²(q) (the value at an extremum is insensitive to the error in q to first
order). The gaps are the complement of the union of the branches' ranges: ordering-independent, so crossing
branches never open a false gap, and a gap narrower than :data:`GAP_RESOLUTION` (relative) is none. Widths in ω are (ω²_up − ω²_low)/(ω_up + ω_low) from the accurate edges (their
relative error grows as ω²/Δω² only for gaps far narrower than the band frequencies).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cell import Cell
from .spectrum import Spectrum, by_continuity, spectrum

#: Default samples of q on [0, π] for edges and extrema.
POINTS = 513
#: Tolerance in q of the extremum search [rad].
Q_TOL = 1e-11
#: Relative width (in ω²) below which two band edges touch: the edges are accurate to a few ulps, so a narrower
#: "gap" cannot be told from none (bands that touch, e.g. at q = π of a folded monatomic chain).
GAP_RESOLUTION = 1e-13


@dataclass(frozen=True)
class Edge:
    """The range of branch ``branch``: lowest ω² at ``q_low``, highest at ``q_high``."""

    branch: int
    low: float
    q_low: float
    high: float
    q_high: float

    @property
    def omega_low(self) -> float:
        return math.sqrt(self.low)

    @property
    def omega_high(self) -> float:
        return math.sqrt(self.high)

    def as_json(self) -> dict:
        return {"branch": self.branch, "omega2_min": self.low, "omega2_max": self.high,
                "omega_min": self.omega_low, "omega_max": self.omega_high, "q_min": self.q_low, "q_max": self.q_high}


@dataclass(frozen=True)
class Gap:
    """A frequency range no branch reaches: from the top of branch ``below`` to the bottom of ``above``."""

    below: int
    above: int
    lower: float  # ω² of the lower edge
    upper: float  # ω² of the upper edge
    q_lower: float
    q_upper: float

    @property
    def omega_lower(self) -> float:
        return math.sqrt(self.lower)

    @property
    def omega_upper(self) -> float:
        return math.sqrt(self.upper)

    @property
    def width(self) -> float:
        """ω_up − ω_low [rad/s], from the ω² edges without a difference of square roots."""
        return (self.upper - self.lower) / (self.omega_upper + self.omega_lower)

    @property
    def centre(self) -> float:
        return 0.5 * (self.omega_upper + self.omega_lower)

    def as_json(self) -> dict:
        return {"below": self.below, "above": self.above, "omega2_lower": self.lower, "omega2_upper": self.upper,
                "omega_lower": self.omega_lower, "omega_upper": self.omega_upper, "width": self.width,
                "centre": self.centre, "q_lower": self.q_lower, "q_upper": self.q_upper}


def turns(v: np.ndarray, resolution: float = 1e-12) -> list[tuple[int, float]]:
    """Interior extrema of sampled values ``v`` as ``(index, +1 a minimum / −1 a maximum)``: where the direction
    changes, steps smaller than ``resolution`` times the largest |v| counting as flat (a flat branch's rounding
    is no extremum)."""
    step = np.diff(v)
    tol = resolution * max(float(np.max(np.abs(v))), np.finfo(float).tiny)
    direction = np.where(step > tol, 1, np.where(step < -tol, -1, 0))
    out, last, at = [], 0, 0
    for k, d in enumerate(direction):
        if d == 0:
            continue
        if last and d != last:  # the turn lies on the samples between the last move and this one
            lo, hi = at + 1, k
            seg = v[lo:hi + 1]
            best = lo + int(np.argmin(seg) if last < 0 else np.argmax(seg))
            if 0 < best < v.shape[0] - 1:
                out.append((best, 1.0 if last < 0 else -1.0))
        last, at = d, k
    return out


def branch_value(cell: Cell, q: float, reference: np.ndarray) -> tuple[float, np.ndarray]:
    """ω² at ``q`` of the branch whose eigenvector is nearest ``reference`` (shape (p,)), and its eigenvector."""
    s = spectrum(cell, np.array([q]))
    j = int(np.argmax(np.abs(reference.conj() @ s.vectors[0]) ** 2))
    return float(s.omega2[0, j]), s.vectors[0, :, j]


def _refine(cell: Cell, qs: np.ndarray, spec: Spectrum, j: int, k: int, sign: float) -> tuple[float, float]:
    """The extremum of branch j near grid point k (sign +1 a minimum, −1 a maximum): (ω², q)."""
    from scipy.optimize import minimize_scalar

    ref = spec.vectors[k, :, j]
    lo, hi = qs[k - 1], qs[k + 1]
    res = minimize_scalar(lambda x: sign * branch_value(cell, x, ref)[0], bounds=(lo, hi), method="bounded",
                          options={"xatol": Q_TOL})
    best = float(res.x)
    value = branch_value(cell, best, ref)[0]
    grid = float(spec.omega2[k, j])
    return (value, best) if sign * value <= sign * grid else (grid, float(qs[k]))


def edges(cell: Cell, points: int = POINTS) -> tuple[list[Edge], list[Gap], Spectrum]:
    """The range of every branch and the gaps between them.

    Returns
    -------
    edges : list of Edge, one per branch (continuity order)
    gaps : list of Gap, ascending
    grid : Spectrum on ``points`` q from 0 to π, branches by continuity
    """
    qs = np.linspace(0.0, np.pi, max(int(points), 3))
    spec, _ = by_continuity(spectrum(cell, qs), cell)
    out = []
    for j in range(cell.p):
        v = spec.omega2[:, j]
        lows = [(float(v[0]), 0.0), (float(v[-1]), float(qs[-1]))]
        highs = list(lows)
        for k, sign in turns(v):
            (lows if sign > 0 else highs).append(_refine(cell, qs, spec, j, k, sign))
        lo, hi = min(lows), max(highs)
        out.append(Edge(j, lo[0], lo[1], hi[0], hi[1]))
    return out, gaps_of(out), spec


def gaps_of(ranges: list[Edge]) -> list[Gap]:
    """The gaps between the union of the branch ranges, ascending."""
    gaps = []
    order = sorted(ranges, key=lambda e: (e.low, e.high))
    top = order[0]
    for e in order[1:]:
        if e.low - top.high > GAP_RESOLUTION * e.low:
            gaps.append(Gap(top.branch, e.branch, top.high, e.low, top.q_high, e.q_low))
        if e.high > top.high:
            top = e
    return gaps


__all__ = ["POINTS", "Edge", "Gap", "branch_value", "edges", "gaps_of", "turns"]
