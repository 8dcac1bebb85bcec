"""Modes refined to double-double from the elements: the shapes every sensitivity is built on.

The float64 modes of the spring-factor SVD are accurate to ε in the mass-weighted norm, which is
not enough for the strain energy of a stiff spring between light masses (its stretch is a
difference of nearly equal displacements: errors of ~ε·ω_max/ω_j in the normalised sensitivity,
1.9e-12 measured at a 1e12 contrast). Each mode (each cluster of repeated ω² together) is refined
by Newton's correction ``φ ← φ − (K − λM)⁺ (K φ − λ M φ)`` with the residual computed from the
elements in double-double (:class:`.double_double.Stencil`) and λ the double-double Rayleigh
quotient ``Σ k_s (φ_a − φ_b)² / Σ m_i φ_i²``; the corrector is float64 (:mod:`.solvers`). Two or
three steps settle 30 digits.

``refine_cluster`` works for any corrector; :func:`dense_modes` and :func:`chain_modes` start it
from the accurate float64 modes of a dense scene or from bisection and inverse iteration on an
open chain (O(n) per mode).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from . import double_double as ddm

#: Modes whose float64 ω² differ by at most this (relative) form one repeated ω² (a cluster): the
#: spring-factor ω² are accurate to ~2e-15, so this is 50 times their error.
CLUSTER_RTOL = 1e-13
#: A correction below this (M-norm; shapes have norm 1) ends the refinement.
SETTLED = 1e-24
#: Most refinement steps.
MAX_STEPS = 8


@dataclass(frozen=True)
class RefinedModes:
    """Modes in double-double, M-normalised, ascending.

    Attributes
    ----------
    index : ndarray of int, shape (J,)
        Each mode's position among all modes in ascending ω² (rigid modes first).
    omega2 : (ndarray, ndarray)
        ω², double-double, shape (J,) each.
    shapes : (ndarray, ndarray)
        Physical shapes with ``φᵀMφ = 1``, double-double, shape (N, J) each; the sign makes the
        largest mass-weighted component positive.
    cluster : ndarray of int, shape (J,)
        Modes with the same label share one repeated ω² (labels are the first index of the cluster).
    rigid : ndarray of bool, shape (J,)
        Rigid-body modes (ω² = 0 exactly, by structure).
    twist : ndarray of int, shape (J,)
        The largest mass-weighted component of each mode (Nelson's deleted row).
    settled : ndarray, shape (J,)
        The last correction's size (M-norm): the shapes' accuracy.
    """

    index: np.ndarray
    omega2: tuple = field(repr=False)
    shapes: tuple = field(repr=False)
    cluster: np.ndarray = field(repr=False)
    rigid: np.ndarray = field(repr=False)
    twist: np.ndarray = field(repr=False)
    settled: np.ndarray = field(repr=False)

    @property
    def omega2_values(self) -> np.ndarray:
        return ddm.to_float(self.omega2)

    @property
    def shape_values(self) -> np.ndarray:
        return ddm.to_float(self.shapes)

    def column(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Shape ``j`` (a position in this set), double-double, shape (N,)."""
        return self.shapes[0][:, j], self.shapes[1][:, j]


def m_norm2(stencil: ddm.Stencil, x) -> tuple[float, float]:
    """``xᵀ M x`` (double-double) of one shape."""
    return ddm.dot_weighted(x, stencil.masses, x)


def normalise(stencil: ddm.Stencil, x):
    """``x / √(xᵀMx)`` in double-double."""
    s = m_norm2(stencil, x)
    r = ddm.sqrt((np.float64(s[0]), np.float64(s[1])))
    return ddm.div(x, (np.full_like(x[0], r[0]), np.full_like(x[0], r[1])))


def rayleigh(stencil: ddm.Stencil, k: np.ndarray, x) -> tuple[float, float]:
    """``Σ k_s (x_a − x_b)² / Σ m x²`` (double-double; sums of non-negative terms)."""
    st = stencil.stretches(x)
    num = ddm.total(ddm.mul_f(ddm.mul(st, st), k))
    den = m_norm2(stencil, x)
    q = ddm.div((np.float64(num[0]), np.float64(num[1])), (np.float64(den[0]), np.float64(den[1])))
    return float(q[0]), float(q[1])


def orthonormalise(stencil: ddm.Stencil, cols: list) -> list:
    """Modified Gram–Schmidt in the M inner product, double-double (a cluster's shapes)."""
    out = []
    for x in cols:
        for y in out:
            c = ddm.dot_weighted(y, stencil.masses, x)
            x = ddm.sub(x, ddm.mul(y, (np.float64(c[0]), np.float64(c[1]))))
        out.append(normalise(stencil, x))
    return out


def refine_cluster(stencil: ddm.Stencil, k: np.ndarray, shapes: np.ndarray,
                   correct: Callable[[np.ndarray, float], np.ndarray]):
    """Newton-refine the shapes of one cluster (one repeated ω², or one simple mode).

    Parameters
    ----------
    stencil : Stencil
    k : ndarray, shape (S,)
    shapes : ndarray, shape (N, r)
        float64 starting shapes (any scale).
    correct : callable
        ``correct(r, lam) -> v`` with ``(K − λM) v ≈ r`` on the complement of the cluster.

    Returns
    -------
    lam : list of (float, float)
        Each shape's Rayleigh quotient.
    cols : list of double-double shapes, each shape (N,)
        M-orthonormal.
    settled : float
        The last correction's size.
    """
    cols = orthonormalise(stencil, [ddm.dd(shapes[:, a]) for a in range(shapes.shape[1])])
    last = np.inf
    lam = [rayleigh(stencil, k, x) for x in cols]
    for _ in range(MAX_STEPS):
        size = 0.0
        new = []
        for x, q in zip(cols, lam):
            r = ddm.to_float(stencil.residual(k, q, x))
            v = correct(-r, q[0] + q[1])
            if not np.all(np.isfinite(v)):
                v = np.zeros_like(v)
            size = max(size, float(np.sqrt(np.sum(stencil.masses * v * v))))
            new.append(ddm.add(x, ddm.dd(v)))
        if not size < last:  # no longer contracting: keep the previous shapes
            break
        cols = orthonormalise(stencil, new)
        lam = [rayleigh(stencil, k, x) for x in cols]
        last = size
        if size <= SETTLED:
            break
    return lam, cols, last


def clusters(omega2: np.ndarray, rigid: int) -> np.ndarray:
    """Cluster labels of ascending ω² (rigid modes one cluster; elastic ones within
    :data:`CLUSTER_RTOL`)."""
    w2 = np.asarray(omega2, dtype=float)
    label = np.arange(w2.shape[0])
    label[:rigid] = 0
    for j in range(max(rigid, 1), w2.shape[0]):
        if j > rigid and w2[j] - w2[j - 1] <= CLUSTER_RTOL * abs(w2[j]):
            label[j] = label[j - 1]
    return label


def _sign(phi: np.ndarray, masses: np.ndarray) -> np.ndarray:
    """The largest mass-weighted component of each shape positive (the spectrum's convention)."""
    u = phi * np.sqrt(masses)[:, None]
    big = np.argmax(np.abs(u), axis=0)
    return np.where(u[big, np.arange(u.shape[1])] < 0, -1.0, 1.0)


def assemble_refined(stencil, index, lam, cols, label, rigid, settled) -> RefinedModes:
    hi = np.stack([c[0] for c in cols], axis=1) if cols else np.zeros((stencil.n, 0))
    lo = np.stack([c[1] for c in cols], axis=1) if cols else np.zeros((stencil.n, 0))
    sign = _sign(hi, stencil.masses) if cols else np.zeros(0)
    hi, lo = hi * sign[None, :], lo * sign[None, :]
    twist = np.argmax(np.abs(hi * np.sqrt(stencil.masses)[:, None]), axis=0) if cols else np.zeros(0, np.intp)
    w_hi = np.array([q[0] for q in lam])
    w_lo = np.array([q[1] for q in lam])
    return RefinedModes(np.asarray(index, dtype=np.intp), (w_hi, w_lo), (hi, lo), np.asarray(label, dtype=np.intp),
                        np.asarray(rigid, dtype=bool), np.asarray(twist, dtype=np.intp),
                        np.asarray(settled, dtype=float))


def rigid_shape(stencil: ddm.Stencil, piece_vector: np.ndarray):
    """The M-normalised uniform translation of a free piece (``piece_vector``: 1 on the piece, 0 off)."""
    return normalise(stencil, ddm.dd(piece_vector))


def dense_modes(stencil: ddm.Stencil, k: np.ndarray, spectrum, wanted: np.ndarray | None = None):
    """Refined modes of any scene from its accurate float64 spectrum (:class:`numeric.modes.spectrum.Spectrum`).

    Parameters
    ----------
    stencil : Stencil
    k : ndarray, shape (S,)
    spectrum : Spectrum
        ``omega``, ``vectors`` (mass-weighted, orthonormal), ``rigid``.
    wanted : ndarray of int, optional
        Mode positions to refine (whole clusters are refined together); default all.

    Returns
    -------
    RefinedModes
    solver : ModalSolver
        The corrector (for Nelson's systems).
    """
    from .solvers import ModalSolver

    n, r = stencil.n, spectrum.rigid
    w2 = np.asarray(spectrum.omega, dtype=float) ** 2
    label = clusters(w2, r)
    wanted = np.arange(n) if wanted is None else np.unique(np.asarray(wanted, dtype=np.intp))
    solver = ModalSolver(stencil.masses, spectrum.vectors, w2)
    phi0 = spectrum.vectors / np.sqrt(stencil.masses)[:, None]
    index, lam, cols, rig, lab, settled = [], [], [], [], [], []
    for c in np.unique(label[wanted]):
        members = np.flatnonzero(label == c)
        take = members  # a repeated ω² is taken whole: its derivatives need the whole cluster
        if c < r:
            for j in take:  # rigid: the structural translation of its piece (exact zero ω²)
                piece = (np.abs(spectrum.vectors[:, j]) > 0).astype(float)
                cols.append(rigid_shape(stencil, piece))
                lam.append((0.0, 0.0))
                index.append(j), rig.append(True), lab.append(0), settled.append(0.0)
            continue
        q, xs, last = refine_cluster(stencil, k, phi0[:, members],
                                     lambda rr, lm, m=members: solver.solve(rr, lm, m))
        for a, j in enumerate(members):
            if j in take:
                index.append(j), lam.append(q[a]), cols.append(xs[a]), rig.append(False)
                lab.append(int(c)), settled.append(last)
    order = np.argsort(index, kind="stable")
    pick = lambda seq: [seq[i] for i in order]  # noqa: E731
    return assemble_refined(stencil, pick(index), pick(lam), pick(cols), pick(lab), pick(rig), pick(settled)), solver


__all__ = ["RefinedModes", "refine_cluster", "dense_modes", "clusters", "normalise", "rayleigh",
           "orthonormalise", "m_norm2", "CLUSTER_RTOL"]
