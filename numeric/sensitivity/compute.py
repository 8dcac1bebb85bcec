"""Sensitivities of a scene's modes at its parameter values: the route for each kind of scene.

* ``[masses]`` scenes and rings: the accurate spring-factor modes (:attr:`System.spectrum`) refined to
  double-double (:func:`.refine.dense_modes`), Nelson's systems through the modal corrector;
  up to :data:`DENSE_MAX` masses (the spectrum is O(N³)).
* open ``[chain]`` scenes: bisection and Nelson's tridiagonal system, O(n) per mode and parameter
  (:func:`.chain.chain_modes`), any length.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import RunRefused
from ..system import System
from . import double_double as ddm
from .derivatives import ElementDerivatives, derivatives
from .refine import CLUSTER_RTOL

#: Largest dense scene (masses) whose sensitivities are computed (the spectrum is O(N³), ~6 s at 2000).
DENSE_MAX = 2000


@dataclass(frozen=True)
class ModeSensitivities:
    """Derivatives of modes with respect to parameters (see :mod:`.derivatives` for the conventions).

    Attributes
    ----------
    parameters : tuple of str
    values : tuple of float
    index : ndarray of int, shape (J,)
        Mode positions in ascending ω² (0-based, rigid modes first).
    omega2 : ndarray, shape (J,)
    shapes : ndarray, shape (N, J)
        M-normalised shapes (``φᵀMφ = 1``; largest mass-weighted component positive).
    cluster : ndarray of int, shape (J,)
        Equal labels: one repeated ω².
    rigid : ndarray of bool, shape (J,)
    d_omega2 : ndarray, shape (P, J)
    d_shapes : ndarray, shape (P, N, J)
    adapted : ndarray, shape (P, N, J)
        The shape each ``d_shapes`` column is the derivative of (``shapes`` except in a repeated ω²
        split by the parameter: its adapted basis).
    settled : ndarray, shape (J,)
        Size of each shape's last double-double correction (M-norm).
    route : str
    """

    parameters: tuple[str, ...]
    values: tuple[float, ...]
    index: np.ndarray = field(repr=False)
    omega2: np.ndarray = field(repr=False)
    shapes: np.ndarray = field(repr=False)
    cluster: np.ndarray = field(repr=False)
    rigid: np.ndarray = field(repr=False)
    d_omega2: np.ndarray = field(repr=False)
    d_shapes: np.ndarray = field(repr=False)
    adapted: np.ndarray = field(repr=False)
    settled: np.ndarray = field(repr=False)
    route: str = ""

    @property
    def normalised(self) -> np.ndarray:
        """``p/ω² · ∂ω²/∂p`` (dimensionless; NaN for rigid modes), shape (P, J)."""
        p = np.asarray(self.values, dtype=float)[:, None]
        w2 = np.where(self.rigid, np.nan, self.omega2)[None, :]
        with np.errstate(invalid="ignore", divide="ignore"):
            return p * self.d_omega2 / w2

    @property
    def repeated(self) -> np.ndarray:
        """How many modes share each mode's ω², shape (J,)."""
        labels, counts = np.unique(self.cluster, return_counts=True)
        return counts[np.searchsorted(labels, self.cluster)]


def open_chain(system: System) -> bool:
    """An open ``[chain]`` (free or wall ends, no ring closure): the O(n) route applies."""
    from ...generated.contract import End

    return system.chain and End.RING not in system.ends


def compute(system: System, derivs: ElementDerivatives, wanted: np.ndarray | None = None) -> ModeSensitivities:
    """Sensitivities of the modes ``wanted`` (positions, default all) of a linear system.

    Parameters
    ----------
    system : System
        The generated module at the parameter values (masses, springs).
    derivs : ElementDerivatives
        ∂/∂p of the masses and spring constants (``system``'s order).
    wanted : ndarray of int, optional

    Returns
    -------
    ModeSensitivities

    Raises
    ------
    RunRefused
        A closed ring or ``[masses]`` scene of more than :data:`DENSE_MAX` masses.
    """
    masses, ends, k = system.masses, system.spring_ends, system.stiffness
    n = masses.shape[0]
    wanted = np.arange(n) if wanted is None else np.asarray(wanted, dtype=np.intp)
    if wanted.size and (wanted.min() < 0 or wanted.max() >= n):
        raise RunRefused(f"modes {wanted.tolist()}: accepted: positions 0 ... {n - 1}", "modes")
    stencil = ddm.Stencil(masses, ends)
    if open_chain(system):
        from .chain import chain_modes

        modes, solver = chain_modes(stencil, ends, k, wanted)
        solve = lambda r, lam, cluster, twist: solver.solve(r, lam, twist)  # noqa: E731
        route = ("open chain: bisection on the bidiagonal spring factor, Nelson's tridiagonal system, "
                 "double-double residuals from the elements (O(n) per mode and parameter)")
    else:
        if n > DENSE_MAX:
            raise RunRefused(f"sensitivities of a {'ring' if system.chain else 'scene'} of {n} masses: the dense "
                             f"modes are O(N^3); accepted: at most {DENSE_MAX} masses, or an open [chain] "
                             f"(O(n) per mode)")
        from .refine import dense_modes

        modes, solver = dense_modes(stencil, k, system.spectrum, wanted)
        solve = lambda r, lam, cluster, twist: solver.solve(r, lam, cluster)  # noqa: E731
        route = ("spring-factor SVD modes refined by Newton steps with double-double residuals from the "
                 "elements; Nelson's systems through the modal corrector")
    d = derivatives(stencil, k, modes, solve, derivs)
    d_w2, d_phi = _settle(d.d_omega2, d.d_shapes, modes.omega2_values, masses, derivs.values)
    d_w2 = _resolve_small(d_w2, d.shapes, modes.omega2_values, ends, derivs, _simple(modes.cluster))
    return ModeSensitivities(tuple(derivs.parameters), tuple(derivs.values), modes.index, modes.omega2_values,
                             modes.shape_values, modes.cluster, modes.rigid, d_w2, d_phi, d.shapes,
                             modes.settled, route)


#: Derivatives below this fraction of their scale (ω²/|p|, and 1/|p| for mass-weighted shape components)
#: are double-double noise around an exact zero, far below the 1e-12 the routes guarantee: printed as 0.
NOISE = 1e-24


def _settle(d_w2: np.ndarray, d_phi: np.ndarray, omega2: np.ndarray, masses: np.ndarray, values) -> tuple:
    """Zeros for the double-double noise of exactly vanishing derivatives (see :data:`NOISE`)."""
    p = np.abs(np.asarray(values, dtype=float))[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        w_scale = np.where(p > 0, np.abs(omega2)[None, :] / p, 0.0)
        s_scale = np.where(p > 0, 1.0 / p, 0.0)[:, :, None]
    d_w2 = np.where(np.abs(d_w2) <= NOISE * w_scale, 0.0, d_w2)
    weighted = np.abs(d_phi) * np.sqrt(masses)[None, :, None]
    d_phi = np.where(weighted <= NOISE * s_scale, 0.0, d_phi)
    return d_w2, d_phi




def _simple(cluster: np.ndarray) -> np.ndarray:
    """Whether each mode's ω² is simple (its cluster label shared with no other mode), shape (J,)."""
    labels, counts = np.unique(cluster, return_counts=True)
    return np.isin(cluster, labels[counts == 1])


#: Entries of (parameters × springs × modes) evaluated at once by :func:`_resolve_small`.
_CHUNK = 4_000_000


def _resolve_small(d_w2: np.ndarray, shapes: np.ndarray, omega2: np.ndarray, ends: np.ndarray,
                   derivs: ElementDerivatives, simple: np.ndarray) -> np.ndarray:
    """A derivative :func:`_settle` set to 0 (below double-double's resolution of ω²/p) that is not 0:
    for a simple ω², ``∂ω²/∂p = Σ_s ∂k_s/∂p (φ_a − φ_b)² − ω² Σ_i ∂m_i/∂p φ_i²`` from the refined
    M-normalised shape, which is accurate component by component — each term relative to itself, so a
    spring whose stretch is 1e-20 of the shape's scale still gives its (φ_a − φ_b)². Kept where it is
    above 64 times its own rounding bound (stretches formed in float64, terms of both signs summed),
    else the 0 stays. ``shapes`` (P, N, J), ``omega2`` (J,), ``ends`` (S, 2) with −1 a wall."""
    cols = np.flatnonzero((d_w2 == 0).any(axis=0) & simple)
    if not cols.size:
        return d_w2
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    a, b = ends[:, 0], ends[:, 1]
    dk, dm = np.asarray(derivs.dk, dtype=float), np.asarray(derivs.dm, dtype=float)
    P, S = dk.shape
    out = d_w2.copy()
    eps = float(np.finfo(float).eps)
    step = max(1, _CHUNK // max(1, P * max(S, shapes.shape[1])))
    for lo in range(0, cols.size, step):  # chunks of modes (no loop over masses or springs)
        c = cols[lo:lo + step]
        phi = shapes[:, :, c]  # (P, N, C)
        pa = np.where((a >= 0)[None, :, None], phi[:, np.maximum(a, 0), :], 0.0)  # (P, S, C)
        pb = np.where((b >= 0)[None, :, None], phi[:, np.maximum(b, 0), :], 0.0)
        st = pa - pb
        tk = dk[:, :, None] * st * st
        tm = omega2[c][None, None, :] * dm[:, :, None] * phi * phi
        value = tk.sum(axis=1) - tm.sum(axis=1)  # (P, C)
        bound = 8 * eps * ((np.abs(dk)[:, :, None] * (np.abs(st) * (np.abs(pa) + np.abs(pb)) + st * st)).sum(axis=1)
                           + np.abs(tm).sum(axis=1))
        zero = out[:, c] == 0
        out[:, c] = np.where(zero & (np.abs(value) > 64 * bound), value, out[:, c])
    return out


def mode_shapes(system: System, wanted: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(positions, ω², M-normalised shapes (N, J))`` of the modes ``wanted`` (default all), without
    derivatives: the accurate spectrum (dense scenes), or bisection and refined shapes (open chains,
    O(n) per mode)."""
    masses, ends, k = system.masses, system.spring_ends, system.stiffness
    n = masses.shape[0]
    wanted = np.arange(n) if wanted is None else np.asarray(wanted, dtype=np.intp)
    if open_chain(system) and n > 64:
        from .chain import chain_modes

        modes, _ = chain_modes(ddm.Stencil(masses, ends), ends, k, wanted)
        return modes.index, modes.omega2_values, modes.shape_values
    if n > DENSE_MAX:
        raise RunRefused(f"mode shapes of a {'ring' if system.chain else 'scene'} of {n} masses: accepted: at "
                         f"most {DENSE_MAX} masses, or an open [chain]")
    spec = system.spectrum
    shapes = spec.shapes
    return wanted, spec.omega2[wanted], shapes[:, wanted]


__all__ = ["ModeSensitivities", "compute", "mode_shapes", "open_chain", "DENSE_MAX", "CLUSTER_RTOL"]
