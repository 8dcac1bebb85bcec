"""∂ω²/∂p and ∂φ/∂p of refined modes: the eigenvalue derivative, degenerate perturbation theory and
Nelson's method.

Notation: ``K φ = λ M φ`` with ``λ = ω²`` and the **mass normalisation** ``φᵀMφ = 1``, the sign of φ
fixed so that its largest mass-weighted component ``√m_i φ_i`` is positive. ``K' = Bᵀ diag(∂k/∂p) B``
and ``M' = diag(∂m/∂p)`` come from the derivatives of the element values (masses, spring constants)
with respect to one parameter p.

* **Simple ω²**: ``∂λ/∂p = φᵀ(K' − λM')φ`` (= ``φᵀ(K' − λM')φ / φᵀMφ``), summed over springs
  ``Σ ∂k_s/∂p (φ_a − φ_b)²`` and masses ``− λ Σ ∂m_i/∂p φ_i²`` in double-double.
* **Repeated ω²** (a cluster Φ_C of r modes): the branches through the crossing have the derivatives
  μ_1 ≤ … ≤ μ_r, the eigenvalues of the projected matrix ``A = Φ_Cᵀ(K' − λM')Φ_C``, and their
  shapes tend to the adapted basis ``Ψ = Φ_C Z`` (Z the eigenvectors of A): these are the
  one-sided (directional) derivatives in the direction of increasing p, assigned to the cluster's
  modes in ascending order — finite by construction (automatic differentiation of ``eigh`` gives
  NaN here).
* **Shapes (Nelson's method)**: ``(K − λM) v = f`` with ``f = −(K' − λ'M − λM')φ`` has a particular
  solution ``v`` (Nelson's: the row and column of the largest component deleted, ``v_t = 0``; on
  dense scenes the solution M-orthogonal to the cluster); then
  ``∂φ/∂p = v + c φ`` with ``c = −φᵀMv − ½ φᵀM'φ`` (the derivative of ``φᵀMφ = 1``). The system is
  solved by a float64 corrector (:mod:`.solvers`) refined with double-double residuals from the
  elements. In a cluster the directional derivative of each adapted shape ψ_a adds the in-cluster
  part ``Σ_b c_ab ψ_b``: ``c_aa = −½ψ_aᵀM'ψ_a`` and, for μ_a ≠ μ_b, from the second-order equation
  ``c_ab = [½ψ_bᵀ(K'' − 2μ_a M' − λM'')ψ_a + ψ_bᵀ(K' − λM')v_a] / (μ_a − μ_b)``; where p does not
  split the pair (μ_a = μ_b, e.g. a ring's own parameters, which keep its symmetry) the shapes of the
  pair are any orthonormal basis and the convention ``c_ab = −½ψ_bᵀM'ψ_a`` (no rotation within the
  pair) is used.
* **Rigid modes**: ω² = 0 for every p; the M-normalised translation ``φ = 1/√M_piece`` of a free
  piece has ``∂φ/∂p = −½ (∂M_piece/∂p / M_piece) φ``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import double_double as ddm
from .refine import RefinedModes, orthonormalise

#: Nelson's system: refinement steps (double-double residuals) after the first float64 solve.
NELSON_STEPS = 4
#: μ_a and μ_b closer than this (relative to the cluster's scale λ·max|ρ|) count as one: p does not split them.
SPLIT_RTOL = 1e-10


@dataclass(frozen=True)
class ElementDerivatives:
    """First and second derivatives of every element value with respect to each parameter.

    Attributes
    ----------
    parameters : tuple of str
    values : tuple of float
        The parameters' values.
    dm, d2m : ndarray, shape (P, N)
        ∂m_i/∂p and ∂²m_i/∂p².
    dk, d2k : ndarray, shape (P, S)
        ∂k_s/∂p and ∂²k_s/∂p² (springs in the generated module's order).
    """

    parameters: tuple[str, ...]
    values: tuple[float, ...]
    dm: np.ndarray = field(repr=False)
    dk: np.ndarray = field(repr=False)
    d2m: np.ndarray = field(repr=False)
    d2k: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Derivatives:
    """Derivatives of refined modes with respect to each parameter.

    Attributes
    ----------
    d_omega2 : ndarray, shape (P, J)
        ∂ω²_j/∂p (directional, ascending within a repeated ω²).
    d_shapes : ndarray, shape (P, N, J)
        ∂φ_j/∂p of the mass-normalised shapes (in a repeated ω²: of the adapted shapes ``shapes``).
    shapes : ndarray, shape (P, N, J)
        The shape each derivative belongs to: the modes' shapes, except in a cluster that p splits,
        where the adapted basis of p replaces them.
    """

    d_omega2: np.ndarray = field(repr=False)
    d_shapes: np.ndarray = field(repr=False)
    shapes: np.ndarray = field(repr=False)


def _dd_scalar(x) -> tuple:
    return np.float64(x[0]), np.float64(x[1])


def _col(x):
    """A double-double (N,) shape as a column (N, 1)."""
    return x[0][:, None], x[1][:, None]


def _apply(stencil: ddm.Stencil, dk: np.ndarray, dm: np.ndarray, lam, x):
    """``(K' − λM') x`` in double-double, x shape (N,)."""
    return ddm.sub(stencil.stiffness(dk, x), ddm.mul(ddm.mul_f(x, dm), lam))


def _inner(stencil, x, y, weights=None):
    """``xᵀ W y`` over the first axis (W = M by default), double-double."""
    w = stencil.masses if weights is None else weights
    return ddm.dot_weighted(x, w, y)


def _form(stencil, dk, dm, lam, x, y):
    """``xᵀ(K' − λM')y``, double-double (x, y shape (N,))."""
    return ddm.dot_weighted(x, np.ones(stencil.n), _apply(stencil, dk, dm, lam, y))


class Nelson:
    """Solutions of ``(K − λM) v = f`` (f shape (N,) or (N, P)), refined with double-double residuals.

    Parameters
    ----------
    stencil, k : the elements
    solve : callable
        ``solve(r, lam) -> v`` the float64 corrector (complement of the cluster, or the deleted row).
    lam : (float, float)
    """

    def __init__(self, stencil: ddm.Stencil, k: np.ndarray, solve, lam):
        self.stencil, self.k, self._solve, self.lam = stencil, k, solve, lam

    def __call__(self, f):
        lam_f = float(self.lam[0] + self.lam[1])
        v = ddm.dd(self._solve(ddm.to_float(f), lam_f))
        last = np.inf
        for _ in range(NELSON_STEPS):
            r = ddm.sub(f, self.stencil.residual(self.k, self.lam, v))
            dv = self._solve(ddm.to_float(r), lam_f)
            if not np.all(np.isfinite(dv)):
                break
            size = float(np.max(np.abs(dv), initial=0.0))
            if not size < last:  # no longer contracting
                break
            v = ddm.add(v, ddm.dd(dv))
            last = size
            if size <= 1e-26 * max(float(np.max(np.abs(v[0]), initial=0.0)), 1e-300):
                break
        return v


def _project_out(stencil, v, basis):
    """``v − Σ ψ (ψᵀMv)`` in double-double (v M-orthogonal to the cluster)."""
    for y in basis:
        c = _inner(stencil, y, v)
        v = ddm.sub(v, ddm.mul(y, _dd_scalar(c)))
    return v


def simple_derivatives(stencil: ddm.Stencil, k: np.ndarray, lam, x, solve, derivs: "ElementDerivatives",
                       rigid: bool):
    """Derivatives of one simple (or rigid) mode along every parameter at once.

    Parameters
    ----------
    lam : (float, float)
    x : double-double shape (N,), M-normalised
    solve : callable
        ``solve(r, lam) -> v``, r shape (N, P).
    derivs : ElementDerivatives

    Returns
    -------
    mu : ndarray, shape (P,)
    d : double-double, shape (N, P)
    """
    dmT = derivs.dm.T  # (N, P)
    xc = _col(x)
    half_g = ddm.total(ddm.mul(ddm.mul_f(ddm.mul(xc, xc), dmT), (np.float64(-0.5), np.float64(0.0))))  # −½ xᵀM'x
    if rigid:
        return np.zeros(dmT.shape[1]), ddm.mul(xc, (half_g[0][None, :], half_g[1][None, :]))
    st = stencil.stretches(x)
    stc = _col(st)
    Kx = stencil.spread(ddm.mul_f(stc, derivs.dk.T))  # K'x, (N, P)
    Mpx = ddm.mul_f(xc, dmT)  # M'x
    mu = ddm.sub(ddm.total(ddm.mul_f(ddm.mul(stc, stc), derivs.dk.T)),
                 ddm.mul(ddm.total(ddm.mul(Mpx, xc)), lam))  # xᵀK'x − λ xᵀM'x, (P,)
    Mx = _col(ddm.mul_f(x, stencil.masses))
    f = ddm.neg(ddm.sub(ddm.sub(Kx, ddm.mul(Mx, (mu[0][None, :], mu[1][None, :]))), ddm.mul(Mpx, lam)))
    v = Nelson(stencil, k, solve, lam)(f)
    c = ddm.add(ddm.neg(ddm.total(ddm.mul(Mx, v))), half_g)  # c = −φᵀMv − ½φᵀM'φ
    d = ddm.add(v, ddm.mul(xc, (c[0][None, :], c[1][None, :])))
    return ddm.to_float(mu), d


def cluster_derivatives(stencil: ddm.Stencil, k: np.ndarray, lam, cols: list, solve,
                        dk, dm, d2k, d2m):
    """Directional derivatives along one parameter of a repeated ω² (degenerate perturbation theory).

    Parameters
    ----------
    lam : (float, float)
        The cluster's λ (double-double).
    cols : list of double-double shapes (N,)
        The cluster's M-orthonormal shapes.
    solve : callable
        ``solve(r, lam) -> v`` M-orthogonal to the cluster.
    dk, dm, d2k, d2m : ndarray
        Element derivatives along p.

    Returns
    -------
    mu : ndarray, shape (r,)
        ∂λ/∂p of each branch (in the order of ``shapes``; not sorted).
    shapes : list of double-double (N,)
        The adapted shapes.
    d_shapes : list of double-double (N,)
        Their derivatives.
    """
    r = len(cols)
    A = np.zeros((r, r))
    for a in range(r):
        for b in range(a, r):
            v = _form(stencil, dk, dm, lam, cols[a], cols[b])
            A[a, b] = A[b, a] = v[0] + v[1]
    _, Z = np.linalg.eigh(A)
    psi = []
    for a in range(r):
        acc = (np.zeros(stencil.n), np.zeros(stencil.n))
        for b in range(r):
            acc = ddm.add(acc, ddm.mul_f(cols[b], Z[b, a]))
        psi.append(acc)
    psi = orthonormalise(stencil, psi)
    root = np.sqrt(stencil.masses)
    for a, x in enumerate(psi):  # the modes' sign convention: the largest mass-weighted component positive
        big = int(np.argmax(np.abs(x[0] * root)))
        if x[0][big] < 0:
            psi[a] = ddm.neg(x)
    mus = [_dd_scalar(_form(stencil, dk, dm, lam, x, x)) for x in psi]
    vs = []
    for a, x in enumerate(psi):
        f = ddm.neg(ddm.sub(_apply(stencil, dk, dm, lam, x), ddm.mul(ddm.mul_f(x, stencil.masses), mus[a])))
        vs.append(_project_out(stencil, Nelson(stencil, k, solve, lam)(f), psi))
    scale = abs(float(lam[0])) * max(np.max(np.abs(dk / np.where(k > 0, k, 1.0)), initial=0.0),
                                     np.max(np.abs(dm / stencil.masses), initial=0.0), 1e-300)
    out = []
    for a, x in enumerate(psi):
        v = vs[a]
        g = _inner(stencil, x, x, dm)
        c = ddm.add(ddm.neg(_inner(stencil, x, v)), (-0.5 * np.float64(g[0]), -0.5 * np.float64(g[1])))
        d = ddm.add(v, ddm.mul(x, _dd_scalar(c)))
        for b, y in enumerate(psi):
            if b == a:
                continue
            mu_a, mu_b = mus[a][0] + mus[a][1], mus[b][0] + mus[b][1]
            if abs(mu_a - mu_b) > SPLIT_RTOL * scale:
                second = ddm.sub(ddm.sub(stencil.stiffness(d2k, x),
                                         ddm.mul(ddm.mul_f(x, dm), (2 * mus[a][0], 2 * mus[a][1]))),
                                 ddm.mul(ddm.mul_f(x, d2m), lam))
                num = ddm.add(ddm.mul((np.float64(0.5), np.float64(0.0)),
                                      _dd_scalar(ddm.dot_weighted(y, np.ones(stencil.n), second))),
                              _dd_scalar(_form(stencil, dk, dm, lam, y, v)))
                cab = ddm.div(num, ddm.sub(mus[a], mus[b]))
            else:
                gb = _inner(stencil, y, x, dm)
                cab = (-0.5 * np.float64(gb[0]), -0.5 * np.float64(gb[1]))
            d = ddm.add(d, ddm.mul(y, _dd_scalar(cab)))
        out.append(d)
    return np.array([m[0] + m[1] for m in mus]), psi, out


def derivatives(stencil: ddm.Stencil, k: np.ndarray, modes: RefinedModes, solve,
                derivs: ElementDerivatives) -> Derivatives:
    """∂ω²/∂p and ∂φ/∂p of every refined mode along every parameter.

    Parameters
    ----------
    stencil, k : the elements
    modes : RefinedModes
    solve : callable
        ``solve(r, lam, cluster_positions, twist) -> v``.
    derivs : ElementDerivatives
    """
    P, J, n = len(derivs.parameters), modes.index.shape[0], stencil.n
    d_w2 = np.zeros((P, J))
    d_phi = np.zeros((P, n, J))
    shapes = np.zeros((P, n, J))
    for label in np.unique(modes.cluster):
        at = np.flatnonzero(modes.cluster == label)
        positions = modes.index[at]
        lam = (np.float64(np.mean(modes.omega2[0][at])), np.float64(np.mean(modes.omega2[1][at])))
        rigid = bool(modes.rigid[at[0]])
        if rigid or at.size == 1:
            for j in at:
                x = modes.column(j)
                tw = int(modes.twist[j])
                mu, d = simple_derivatives(stencil, k, (modes.omega2[0][j], modes.omega2[1][j]), x,
                                           lambda rr, lm, pos=positions, tw=tw: solve(rr, lm, pos, tw), derivs,
                                           bool(modes.rigid[j]))
                d_w2[:, j] = mu
                d_phi[:, :, j] = ddm.to_float(d).T
                shapes[:, :, j] = ddm.to_float(x)[None, :]
            continue
        cols = [modes.column(j) for j in at]
        for p in range(P):
            mu, psi, dpsi = cluster_derivatives(
                stencil, k, lam, cols, lambda rr, lm, pos=positions: solve(rr, lm, pos, -1),
                derivs.dk[p], derivs.dm[p], derivs.d2k[p], derivs.d2m[p])
            order = np.argsort(mu, kind="stable")
            for slot, a in zip(at, order):
                d_w2[p, slot] = mu[a]
                d_phi[p, :, slot] = ddm.to_float(dpsi[a])
                shapes[p, :, slot] = ddm.to_float(psi[a])
    return Derivatives(d_w2, d_phi, shapes)


__all__ = ["ElementDerivatives", "Derivatives", "derivatives", "simple_derivatives", "cluster_derivatives", "Nelson"]
