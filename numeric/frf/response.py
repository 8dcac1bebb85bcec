"""Frequency response: the receptance ``H(iω) = X_out / F_in`` of a linear scene.

``(K − ω²M + iωC) X = F`` is solved once per frequency with ``F`` the unit force on the input
mass, never from K or C formed in float64 (adding a small spring to a large one rounds it
away): ``[masses]`` scenes by the certified modal solve of :mod:`numeric.frf.dense` (refined with
residuals in extended precision, mpmath where float64 cannot be certified), open ``[chain]``
scenes by dynamic stiffness (:mod:`numeric.frf.chain`, O(n) per frequency, relatively accurate),
rings of at most :data:`RING_DENSE` masses by the certified modal solve as well, longer rings by a
tridiagonal solve with one Sherman–Morrison correction, refined with residuals from the elements,
certified per frequency and refused in one line where that fails at an element contrast above
:data:`RING_CONTRAST` (never an N × N matrix for a long chain). Cubic springs enter by their linear part (the response of the linearisation about
x = 0); gravity, forces and ground motion do not change H.

The grid
--------
A log-spaced grid over ``[omega_min, omega_max]`` (default: the smallest nonzero ω / 10 to the
largest ω · 3, from the accurate spectrum of :mod:`numeric.modes.spectrum`, bisection on the bidiagonal
spring factor for chains, and the damped ω_d of the resonance table), refined around every
resonance in range (at most :data:`MAX_REFINED`, the lowest): points at ``ω_d (1 ± b g)`` for
``g`` log-spaced over three decades around the half-power half-width ``b = ζ``. For a damped
resonance the local maximum of ``|H|`` is then found by a bounded scalar search (each trial is
one more exact solve) and added to the grid, so the printed peak is the exact peak of ``|H|``,
not the nearest grid point.

An **undamped** resonance (ζ = 0: no dampers, or a mode the dampers do not touch) has
``|H| = ∞`` at ``ω_j``: no grid point is put closer to it than :data:`UNDAMPED_GAP` (relative),
the grid approaches it from both sides, and the figure marks ``ω_j`` by a vertical line instead
of a peak.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ...generated.contract import MAX_DENSE, End
from ..errors import RunRefused
from .dense import MPMATH_MAX_MASSES, dense_chunk
from .scaled import split, unscale
from .table import (NARROW_ZETA, NODE_FLOAT, REPEATED, SETTLE_MAX, Resonance, attribute, connected,
                        local_maxima, sees)
from ..system import System

#: Resonances refined (the lowest in range); long chains have more modes than any grid.
MAX_REFINED = 40
#: Extra grid points per refined resonance.
REFINE_POINTS = 24
#: Closest relative distance of a grid point to an undamped ω_j (|H| ∝ 1/gap there).
UNDAMPED_GAP = 1e-4
#: Closest relative distance to an undamped ω_j of a mode with a node at the input or output
#: (H is finite there, but the solve's error grows like 1/gap times |X|/|X_out|).
SILENT_GAP = 1e-2
#: Largest ring solved by the certified modal route of :mod:`numeric.frf.dense` (the tridiagonal
#: solve with a Sherman–Morrison corner loses κ·ε: 1e-9 N/m next to 1e3 N/m springs): the rings
#: whose every frequency it certifies or settles in mpmath.
RING_DENSE = MPMATH_MAX_MASSES
#: Element contrast (largest over smallest spring, dashpot or mass) of a longer ring above which an
#: uncertified frequency is refused; below it the refined tridiagonal value is returned.
RING_CONTRAST = 1e6
#: Largest certified relative error of |H| accepted from the tridiagonal solve of a long ring.
RING_CERTIFIED = 1e-10
#: Refinement steps of a long ring's solve (residuals from the elements) before it is refused.
REFINE_RING = 3


@dataclass(frozen=True)
class Operator:
    """``K``, ``M``, ``C`` of a linear scene, as the solver needs them.

    Dense scenes: ``K``, ``C`` of shape (N, N) and the certified solver ``dense``. Chains: ``K``
    and ``C`` as tridiagonal bands ``(diag (N,), off (N-1,), corner)`` with ``corner`` the coupling
    of masses 0 and N−1 (rings), and for open chains their impedances ``chain``. ``C`` is None
    without damping. An Operator with neither ``dense`` nor ``chain`` solves from K and C in
    float64 (LU, or the tridiagonal solve).
    """

    masses: np.ndarray = field(repr=False)
    K: object = field(repr=False)
    C: object = field(default=None, repr=False)
    banded: bool = False
    dense: object = field(default=None, repr=False)
    chain: object = field(default=None, repr=False)
    #: A long ring's elements (:class:`numeric.modes.elements.Elements`): certify the tridiagonal solve.
    elements: object = field(default=None, repr=False)
    #: Notes the solves leave (a float64 limit met): one line each, collected by the response.
    notes: list = field(default_factory=list, repr=False, compare=False)
    #: What is left of the extended-precision budget of a long chain's sweeps (mass-frequencies).
    budget: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])


def _corner(n: int, ends: np.ndarray, values: np.ndarray) -> float:
    """The coupling ``-Σ k`` of the elements joining masses 0 and n−1 of a ring (n > 2)."""
    ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
    ring = (np.minimum(ends[:, 0], ends[:, 1]) == 0) & (np.maximum(ends[:, 0], ends[:, 1]) == n - 1) & (n > 2)
    return -float(np.sum(np.asarray(values, dtype=float)[ring]))


def _bands_of_dense(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Tridiagonal bands and ring corner of a dense matrix that has no other entries."""
    n = A.shape[0]
    corner = float(A[0, n - 1]) if n > 2 else 0.0
    rest = A - np.diag(np.diag(A)) - np.diag(np.diag(A, 1), 1) - np.diag(np.diag(A, -1), -1)
    if n > 2:
        rest[0, n - 1] = rest[n - 1, 0] = 0.0
    if np.any(rest != 0):
        raise RunRefused("frequency response of a chain: its damping couples masses further apart than "
                         "neighbours (accepted: tridiagonal, ring corners)")
    return np.diag(A).copy(), np.diag(A, 1).copy(), corner


def operator(system: System) -> Operator:
    """The matrices of ``system`` (bands for a ``[chain]``, dense otherwise)."""
    from ..modes.elements import Elements

    el = Elements.from_system(system)
    if not system.chain:
        from .dense import DenseReceptance

        K = system.stiffness_matrix()
        C = system.damping_matrix() if system.damped else None
        return Operator(system.masses, K, C, False, dense=DenseReceptance.from_elements(el))
    n = system.n
    if system.ends[0] is not End.RING:
        zero = (np.zeros(n), np.zeros(max(n - 1, 0)), 0.0)
        if n <= RING_DENSE:  # short chains: the certified modal route (mpmath where float64 cannot certify)
            from .dense import DenseReceptance

            return Operator(system.masses, zero, zero if el.damped else None, True,
                            dense=DenseReceptance.from_elements(el))
        from .chain import chain_elements

        impedances = chain_elements(el.masses, el.spring_ends, el.stiffness, el.damper_ends, el.damping)
        return Operator(system.masses, zero, zero if el.damped else None, True, chain=impedances)
    dense = None
    if n <= RING_DENSE:
        from .dense import DenseReceptance

        dense = DenseReceptance.from_elements(el)
    diag, off = system.stiffness_bands()
    if n == 2 and system.spring_ends.shape[0] > 1:  # a two-mass ring: both springs join 0 and 1
        inner = (system.spring_ends >= 0).all(axis=1)
        off = np.array([-float(system.stiffness[inner].sum())])
    K = (diag, off, _corner(n, system.spring_ends, system.stiffness))
    C = None
    if system.damped:
        try:
            C = _bands_of_dense(system.damping_matrix())
        except ValueError as exc:
            raise RunRefused(f"frequency response of a damped chain of {n} masses: {exc}") from None
    return Operator(system.masses, K, C, True, dense=dense, elements=None if dense is not None else el)


# -- solves -------------------------------------------------------------------------------------------
def receptance(op: Operator, omega: np.ndarray, input: int, output: int, certify: bool = True,
               scaled: bool = False):
    """``H(iω) = X_output / F_input`` of ``(K − ω²M + iωC) X = e_input``.

    Parameters
    ----------
    op : Operator
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s], none exactly on an undamped ω_j.
    input, output : int
        Mass indices.
    certify : bool
        ``[masses]`` scenes: certify each value to 1e-10 (refinement, mpmath where needed); False
        gives the float64 modal solve alone (the peak search's trials).

    scaled : bool
        Return ``(mantissa, expo)``, ``H = mantissa · 2**expo`` (complex (W,), int64 (W,), the mantissa's
        larger part in [1/2, 1)): where |H| is below the float64 range its phase is still that of the
        mantissa (open chains carry the exponent through their sweep; ``[masses]`` scenes solve such
        frequencies in mpmath, :meth:`numeric.frf.dense.DenseReceptance.receptance`).

    Returns
    -------
    ndarray, shape (W,), complex (or the pair above)
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    with np.errstate(all="ignore"):  # float64 overflow is caught below (dense: by its certificate)
        H = _receptance(op, omega, input, output, certify, scaled)
    if scaled:
        H, expo = H
        with np.errstate(all="ignore"):
            big = np.isfinite(H) & ~np.isfinite(unscale(H, expo))
        H = np.where(big, np.inf, H)
    if certify and not np.all(np.isfinite(H)):
        bad = int(np.argmax(~np.isfinite(H)))
        raise RunRefused(f"frequency response at ω = {omega[bad]:.6g} rad/s: H overflows float64 on this route "
                         "(element values near the 1e±150 limits multiplied by ω²); a [masses] scene of at most "
                         f"{MPMATH_MAX_MASSES} masses is solved in extended precision", quantity="frf")
    return (H, expo) if scaled else H


def _receptance(op: Operator, omega: np.ndarray, input: int, output: int, certify: bool, scaled: bool = False):
    if op.dense is not None:
        return op.dense.receptance(omega, input, output, certify=certify, notes=op.notes if certify else None,
                                   scaled=scaled)
    if op.chain is not None:
        from .chain import chain_receptance

        return chain_receptance(op.chain, omega, input, output, certify=certify, notes=op.notes, budget=op.budget,
                                scaled=scaled)
    if scaled:
        return split(_receptance(op, omega, input, output, certify))
    if op.banded:
        return _receptance_banded(op, omega, input, output)
    n = op.n
    M = np.diag(op.masses)
    out = np.empty(omega.shape[0], dtype=complex)
    chunk = dense_chunk(n)
    rhs = np.zeros((n, 1), dtype=complex)
    rhs[input] = 1.0
    for lo in range(0, omega.shape[0], chunk):  # chunks of frequencies, not a loop over masses
        w = omega[lo:lo + chunk]
        Z = op.K[None].astype(complex) - (w**2)[:, None, None] * M[None]
        if op.C is not None:
            Z = Z + 1j * w[:, None, None] * op.C[None]
        out[lo:lo + chunk] = np.linalg.solve(Z, np.broadcast_to(rhs, (w.shape[0], n, 1)))[:, output, 0]
    return out


def _receptance_banded(op: Operator, omega: np.ndarray, input: int, output: int) -> np.ndarray:
    """Tridiagonal (LAPACK ``gtsv``) solve per frequency; a ring corner by Sherman–Morrison. With
    ``op.elements`` (a long ring) each value is refined with residuals from the elements and
    certified (:func:`_certificate`, the corrections kept apart: a double-length solution), or refused
    in one line."""
    kd, ko, kc = op.K
    cd, co, cc = op.C if op.C is not None else (0.0 * kd, 0.0 * ko, 0.0)
    n = op.n
    b = np.zeros((n, 2), dtype=complex)  # the unit force on the input, and on the output (certificate)
    b[input, 0] = 1.0
    b[output, 1] = 1.0
    gtsv = scipy.linalg.lapack.get_lapack_funcs("gtsv", dtype=complex)
    out = np.empty(omega.shape[0], dtype=complex)
    for j, w in enumerate(omega):  # one O(n) tridiagonal solve (LAPACK zgtsv, partial pivoting) per frequency
        diag = kd - w * w * op.masses + 1j * w * cd
        offd = ko + 1j * w * co
        solve = functools.partial(_ring_solve, gtsv, offd, diag, kc + 1j * w * cc)
        y = solve(b[:, :1] if op.elements is None else b)
        out[j] = y[output, 0]
        if op.elements is None:
            continue
        x, x_lo = y[:, 0], np.zeros(n, dtype=complex)  # a double-length solution: corrections kept apart
        for _ in range(REFINE_RING):
            bound, r = _certificate(op.elements, w, x, y[:, 1], input, x_lo)
            if bound <= RING_CERTIFIED * abs(x[output] + x_lo[output]):
                break
            x_lo = x_lo + solve(r[:, None])[:, 0]
        else:
            bound, _ = _certificate(op.elements, w, x, y[:, 1], input, x_lo)
        out[j] = x[output] + x_lo[output]
        if not bound <= RING_CERTIFIED * abs(out[j]) and _contrast(op.elements) > RING_CONTRAST:
            raise RunRefused(
                f"frequency response of a ring of {n} masses at omega = {w:.6g} rad/s: float64 cannot "
                f"certify |H| to {RING_CERTIFIED:g} (error bound {bound / max(abs(out[j]), 1e-300):.2g} "
                f"relative at element contrast {_contrast(op.elements):.2g}); rings of at most {RING_DENSE} "
                "masses are solved accurately at any contrast", quantity="frf")
    return out


def _ring_solve(gtsv, offd: np.ndarray, diag: np.ndarray, a: complex, b: np.ndarray) -> np.ndarray:
    """``X`` of the symmetric tridiagonal system with corner coupling ``a`` (0: none), b shape (n, r)."""
    if a == 0:
        return _gtsv(gtsv, offd, diag.copy(), b)
    diag = diag.copy()
    gamma = -diag[0]  # Z = T' + u vᵀ, u = (γ, 0, …, a), v = (1, 0, …, a/γ)
    diag[0] -= gamma
    diag[-1] -= a * a / gamma
    u = np.zeros((b.shape[0], 1), dtype=complex)
    u[0, 0], u[-1, 0] = gamma, a
    yq = _gtsv(gtsv, offd, diag, np.hstack([b, u]))
    y, q = yq[:, :-1], yq[:, -1]
    vy = y[0] + (a / gamma) * y[-1]
    vq = q[0] + (a / gamma) * q[-1]
    return y - q[:, None] * (vy / (1.0 + vq))[None, :]


def _contrast(el) -> float:
    """Largest over smallest nonzero spring, dashpot and mass of a scene (each kind apart)."""
    out = 1.0
    for v in (el.stiffness, el.damping, el.masses):
        v = np.abs(np.asarray(v, dtype=float))
        v = v[v > 0]
        if v.size:
            out = max(out, float(v.max() / v.min()))
    return out


def _apply(n: int, ends: np.ndarray, values: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``Σ v b bᵀ x`` over elements from their stretches, and ``Σ |v b bᵀ x|`` (what rounding can hide);
    ends (E, 2) with -1 for a wall, values (E,), x (N,); both shape (N,)."""
    a, c = ends[:, 0], ends[:, 1]
    xa = np.where(a >= 0, x[np.maximum(a, 0)], 0.0)
    xc = np.where(c >= 0, x[np.maximum(c, 0)], 0.0)
    f = values * (xa - xc)
    g = np.abs(f)  # the parameters and x are exact binary numbers: only the stretch and force round
    out, hide = np.zeros(n, dtype=x.dtype), np.zeros(n)
    for col, sign in ((a, 1.0), (c, -1.0)):  # the two ends of every element at once
        on = col >= 0
        np.add.at(out, col[on], sign * f[on])
        np.add.at(hide, col[on], g[on])
    return out, hide


def _certificate(el, w: float, x: np.ndarray, y: np.ndarray, input: int,
                 x_lo: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """Bound on the error of ``x_out`` from the residual of ``Z x = e_in`` formed from the elements
    (springs and dashpots by their stretches) and what its rounding can hide, weighted by the
    output's row of Z⁻¹ (``y``, Z symmetric) with a normwise allowance — as :mod:`numeric.frf.dense`;
    returns the bound and the residual, shape (N,)."""
    from .dense import ROW_ALLOWANCE

    n = x.shape[0]
    ends_k = np.asarray(el.spring_ends, dtype=np.intp).reshape(-1, 2)
    ends_c = np.asarray(el.damper_ends, dtype=np.intp).reshape(-1, 2)
    kx, hk = _apply(n, ends_k, np.asarray(el.stiffness, dtype=float), x)
    cx, hc = _apply(n, ends_c, np.asarray(el.damping, dtype=float), x)
    r = -(kx - w * w * el.masses * x + 1j * w * cx)
    r[input] += 1.0
    if x_lo is not None:  # the correction's own residual (small: its rounding is second order)
        kl, _ = _apply(n, ends_k, np.asarray(el.stiffness, dtype=float), x_lo)
        cl, _ = _apply(n, ends_c, np.asarray(el.damping, dtype=float), x_lo)
        r = r - (kl - w * w * el.masses * x_lo + 1j * w * cl)
    hidden = 8 * np.finfo(float).eps * (hk + w * w * el.masses * np.abs(x) + w * hc)
    ay = np.abs(y)
    return float(np.sum((ay + ROW_ALLOWANCE * np.max(ay)) * (np.abs(r) + hidden))), r


def _gtsv(gtsv, off: np.ndarray, diag: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve the symmetric tridiagonal system (off, diag, off) X = b; b shape (n, r)."""
    if diag.shape[0] == 1:
        return b / diag[0]
    _, _, _, x, info = gtsv(off.copy(), diag, off.copy(), b.copy(), overwrite_dl=True, overwrite_d=True,
                            overwrite_du=True, overwrite_b=True)
    if info != 0:
        raise np.linalg.LinAlgError(f"tridiagonal solve: exactly singular at pivot {info}")
    return x


# -- resonances -----------------------------------------------------------------------------------------
def undamped_omegas(system: System, count: int | None = None) -> np.ndarray:
    """Undamped ω ascending (rigid zeros first): the accurate spectrum for ``[masses]`` scenes, the
    closed form or bisection on the bidiagonal spring factor for chains (``count`` lowest plus the
    largest; relatively accurate, O(n) each)."""
    if not system.chain:
        from ..modes.spectrum import spectrum

        return spectrum(system.masses, system.spring_ends, system.stiffness).omega
    n = system.n
    if system.has("mode_omega"):
        return np.sort(system.mode_omega())
    if system.ends[0] is End.RING:
        if n > MAX_DENSE:
            raise RunRefused(f"an index-dependent ring of {n} masses has no closed-form spectrum here; "
                             "give omega_min and omega_max", quantity="omega_min")
        from ..modes.spectrum import spectrum

        return spectrum(system.masses, system.spring_ends, system.stiffness).omega
    from ..modes.chain import bidiagonal_factor, singular_values

    f = bidiagonal_factor(system.masses, system.spring_ends, system.stiffness)
    return singular_values(f) if count is None or count + 1 >= n else singular_values(f, count, 1)


def resonances(system: System, op: Operator, input: int, output: int, omega: np.ndarray | None = None,
               modes: list | None = None, el=None) -> tuple[list[Resonance], str]:
    """Elastic resonances, ascending, and how nodes were judged (:func:`numeric.frf.table.sees`).

    Undamped scenes: the undamped ω_j (ζ = 0). Damped scenes: the damped modes ``modes`` —
    ``(ω_n, ζ, ω_d)`` rows as ``springchain modes`` computes them (the same ζ and ω; rigid and
    overdamped rows, ζ None or ω_d = 0, are no resonance; ζ NaN: not computed) — or, without them,
    the poles of the modal state matrix (``[masses]`` scenes). Every undamped (or narrow) row is
    checked for a node at the input or output. Chains list their :data:`MAX_REFINED` lowest.
    """
    from ..modes.elements import Elements

    el = Elements.from_system(system) if el is None else el
    omega = undamped_omegas(system, MAX_REFINED) if omega is None else omega
    elastic = omega[omega > 0]
    if modes is not None:
        rows = [(float(wn), float("nan") if z is None else float(z), float(wd)) for wn, z, wd in modes
                if wd > 0 and not (z is None and wn == 0)]
    elif op.C is None:
        rows = [(float(w), 0.0, float(w)) for w in elastic]
    elif op.dense is not None:
        rows = [(r.omega_n, r.zeta, r.omega_d) for r in _poles(op.dense)]
    else:  # a damped chain without its modes: ζ not computed
        rows = [(float(w), float("nan"), float(w)) for w in elastic]
    if op.banded:
        rows = rows[:MAX_REFINED]
    ask = [wn for wn, z, _ in rows if 0 <= z < NARROW_ZETA]
    seen = sees(el, ask, input, output)
    flags = iter(seen.flags)
    out = []
    for wn, z, wd in rows:
        sees_it = next(flags) if 0 <= z < NARROW_ZETA else True
        last = out[-1] if out else None
        if (last is not None and abs(wn - last.omega_n) <= REPEATED * wn and abs(wd - last.omega_d) <= REPEATED * wn
                and (z == last.zeta or abs(z - last.zeta) <= REPEATED * max(z, last.zeta))):
            out[-1] = Resonance(last.omega_n, last.zeta, last.omega_d, participates=last.participates,
                                multiplicity=last.multiplicity + 1)  # a repeated frequency: one resonance
            continue
        out.append(Resonance(wn, z, wd, participates=sees_it))
    return out, seen.how


#: ζ of a pole of the float64 state matrix below this is its rounding (an undamped mode).
POLE_NOISE = 1e-13


def _poles(dense) -> list[Resonance]:
    """Oscillatory poles of ``q̈ + G q̇ + Ω² q = 0`` in the accurate modal basis, the state scaled to
    ``(ω q, q̇)`` (balanced: every block of size ω). A rigid mode without damping is a double zero
    (a Jordan block whose eigenvalues rounding splits into ±√ε i): no resonance, and left out. A ζ
    below :data:`POLE_NOISE` is rounding: 0."""
    w, G = dense.omega_n, dense.G
    n = w.shape[0]
    scale = np.where(w > 0, w, 1.0)
    A = np.zeros((2 * n, 2 * n))
    A[np.arange(n), n + np.arange(n)] = scale
    A[n + np.arange(n), np.arange(n)] = -w
    A[n:, n:] = -G
    lam = scipy.linalg.eigvals(A)
    elastic = w[w > 0]
    floor = 1e-4 * float(elastic[0]) if elastic.size else np.inf
    osc = sorted((l for l in lam if l.imag > 1e-12 * abs(l) and abs(l) > floor), key=lambda l: l.imag)
    zeta = [max(-l.real / abs(l), 0.0) for l in osc]
    return [Resonance(float(abs(l)), z if z >= POLE_NOISE else 0.0, float(l.imag)) for l, z in zip(osc, zeta)]


def default_range(res: list[Resonance], omega: np.ndarray) -> tuple[float, float]:
    """``(smallest nonzero ω / 10, largest ω · 3)`` of the undamped ``omega``; refused for a scene
    without an elastic mode."""
    elastic = omega[omega > 0]
    if elastic.size == 0:
        raise RunRefused("the scene has no elastic mode (every ω is 0), so there is no default frequency "
                         "range; give omega_min and omega_max", quantity="omega_min")
    lo = min(float(elastic[0]), min((r.omega_d for r in res if r.omega_d > 0), default=np.inf))
    return lo / 10, float(elastic[-1]) * 3


# -- the response -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Response:
    """A receptance on a refined grid.

    Attributes
    ----------
    omega : ndarray, shape (W,)
        Angular frequencies [rad/s], ascending.
    H : ndarray, shape (W,), complex
        Receptance X_out / F_in [m/N].
    resonances : list of Resonance
        In range, ascending; each damped one with the local maximum of |H| attributed to it.
    connected : bool
        False when no spring or dashpot joins input and output: ``H ≡ 0``.
    extra_peaks : list of (float, float)
        Local maxima ``(ω, |H|)`` of |H| attributed to no resonance.
    notes : list of str
    """

    omega: np.ndarray = field(repr=False)
    H: np.ndarray = field(repr=False)
    resonances: list = field(default_factory=list, repr=False)
    connected: bool = True
    extra_peaks: list = field(default_factory=list, repr=False)
    notes: list = field(default_factory=list, repr=False)
    #: arg H [rad] per frequency, shape (W,) (None: ``np.angle(H)``): right also where |H| is below the
    #: float64 range and H is 0 (from the mantissa of :func:`receptance` with ``scaled``).
    angle: np.ndarray | None = field(default=None, repr=False)

    @property
    def magnitude(self) -> np.ndarray:
        """|H| [m/N], shape (W,)."""
        return np.abs(self.H)

    @property
    def phase(self) -> np.ndarray:
        """Phase of H in degrees, unwrapped along ω, shape (W,)."""
        return np.degrees(np.unwrap(np.angle(self.H) if self.angle is None else self.angle))


def _grid(lo: float, hi: float, points: int, res: list[Resonance]) -> np.ndarray:
    base = np.geomspace(lo, hi, points)
    extra = []
    g = np.geomspace(0.03, 30.0, REFINE_POINTS // 2)
    for r in [r for r in res if r.participates][:MAX_REFINED]:
        widths = [UNDAMPED_GAP / g[0]]  # the gap's scale (undamped, narrow, ζ not computed) ...
        if r.searched and not np.isnan(r.zeta):  # ... and the half-power width of a damped peak
            widths = [r.zeta] + (widths if r.zeta < UNDAMPED_GAP / g[0] else [])
            extra.append([r.omega_d])
        for width in widths:
            near = r.omega_d * np.concatenate([1 - width * g, 1 + width * g])
            extra.append(near[(near > 0)])
    grid = np.union1d(base, np.concatenate(extra)) if extra else base
    grid = grid[(grid >= lo) & (grid <= hi)]
    for r in res:  # never on (or within the gap of) an undamped ω_j
        if r.undamped or r.narrow:  # wider around a mode H does not see: Z is near-singular but H is not large
            gap = UNDAMPED_GAP if r.participates else SILENT_GAP
            grid = grid[np.abs(grid / r.omega_d - 1) >= gap * (1 - 1e-9)]
    return grid


def frequency_response(system: System, input: int, output: int, omega_min: float | None = None,
                       omega_max: float | None = None, points: int = 400, modes: list | None = None) -> Response:
    """The receptance ``X_output / F_input`` on a grid refined at every resonance.

    Parameters
    ----------
    system : System
    input, output : int
        Mass indices (0-based).
    omega_min, omega_max : float, optional
        Range [rad/s]; default from the spectrum (see the module docstring).
    points : int
        Log-spaced base points (the refinement adds up to ``REFINE_POINTS + 2`` per resonance).
    modes : list of (float, float or None, float), optional
        The damped modes ``(ω_n, ζ, ω_d)`` of a damped scene as ``springchain modes`` computes them:
        the resonance table and the default range then use the same numbers.

    Returns
    -------
    Response
    """
    from ..modes.elements import Elements

    el = Elements.from_system(system)
    op = operator(system)
    natural = undamped_omegas(system, MAX_REFINED)
    joined = connected(el, input, output)
    res, how = resonances(system, op, input, output, natural, modes, el) if joined else ([], "mpmath")
    lo, hi = default_range(res, natural) if omega_min is None or omega_max is None else (0.0, 0.0)
    lo = omega_min if omega_min is not None else lo
    hi = omega_max if omega_max is not None else hi
    if not lo < hi:
        raise RunRefused(f"omega_min {lo:g} >= omega_max {hi:g}: accepted: omega_min < omega_max",
                         quantity="omega_min" if omega_min is not None else "omega_max")
    if not joined:  # no spring or dashpot path: H ≡ 0 exactly, nothing to solve
        grid = np.geomspace(lo, hi, points)
        return Response(grid, np.zeros(grid.shape[0], dtype=complex), [], False)
    inside = [r for r in res if lo <= r.omega_d <= hi]
    grid = _grid(lo, hi, points, inside)
    if op.C is not None:  # every undamped ω as well (a damped mode the ζ route missed still shows its peak)
        near = natural[(natural >= lo) & (natural <= hi)][:MAX_REFINED]
        g = np.geomspace(0.03, 30.0, REFINE_POINTS // 2) * UNDAMPED_GAP / 0.03
        extra = (near[:, None] * np.concatenate([1 - g, 1 + g])[None, :]).ravel()
        extra = extra[(extra >= lo) & (extra <= hi)]
        for r in inside:  # kept off the gaps of the singular ones
            if r.undamped or r.narrow:
                extra = extra[np.abs(extra / r.omega_d - 1) >= (UNDAMPED_GAP if r.participates else SILENT_GAP)]
        grid = np.union1d(grid, extra)
    mantissa, expo = receptance(op, grid, input, output, scaled=True)
    notes = []
    H, angle = _below_range(mantissa, expo, notes)
    top = hi
    elastic = natural[natural > 0]
    if op.banded and elastic.shape[0] > MAX_REFINED:
        # a long chain: only its lowest modes are known, so peaks only below the last of them
        top = min(hi, float(elastic[MAX_REFINED - 1]))
        notes.append(f"local maxima of |H| searched below ω = {top:.6g} rad/s (the {MAX_REFINED} lowest modes: "
                     "the grid does not resolve the others)")
    below = grid <= top
    solve = lambda w, certify: receptance(op, w, input, output, certify=certify)  # noqa: E731
    poles = [r.omega_n for r in res if r.singular]
    peaks = local_maxima(solve, grid[below], H[below], poles)
    inside, extra = attribute(inside, [(w, abs(h)) for w, h in peaks])
    if peaks:
        w_p = np.array([w for w, _ in peaks])
        h_p = np.array([h for _, h in peaks], dtype=complex)
        keep = ~np.isin(w_p, grid)
        grid, H = np.concatenate([grid, w_p[keep]]), np.concatenate([H, h_p[keep]])
        angle = np.concatenate([angle, np.angle(h_p[keep])])
        order = np.argsort(grid, kind="stable")
        grid, H, angle = grid[order], H[order], angle[order]
    if how == "float64" and any(not r.participates for r in inside):
        notes.append(f"nodes at the input or output judged in float64 (residue below {NODE_FLOAT:g} of the mode's "
                     f"largest): scenes of more than {SETTLE_MAX} masses are not settled in mpmath")
    if how == "unchecked" and any(r.singular for r in inside):
        notes.append("nodes at the input or output not checked (more than 400 masses): an undamped mode with a "
                     "node there is listed with |H| = ∞ though |H| is finite at it")
    notes += list(dict.fromkeys(op.notes))  # a float64 limit a solve met (each once)
    return Response(grid, H, inside, True, extra, notes, angle)


#: Smallest normal float64: a |H| below it is printed as 0 (a subnormal has lost digits), with a note.
TINY = float(np.finfo(float).tiny)
#: The note of :func:`_below_range` (its start is what tests and callers look for).
BELOW_RANGE = "|H| is below the float64 range"


def _below_range(mantissa: np.ndarray, expo: np.ndarray, notes: list) -> tuple[np.ndarray, np.ndarray]:
    """H from its mantissa and exponent, 0 where |H| is below the smallest normal float64 (subnormals too:
    their digits are lost), and arg H from the mantissa (exact there as well); one note when any is."""
    H = unscale(mantissa, expo)
    with np.errstate(all="ignore"):
        under = (np.abs(H) < TINY) & (mantissa != 0)
    H = np.where(under, 0.0, H)
    if np.any(under):
        notes.append(f"{BELOW_RANGE} (under {TINY:.3g}, the smallest normal float64: printed as 0; the phase is "
                     f"exact) at {int(under.sum())} of {H.shape[0]} frequencies (a far, strongly attenuated transfer)")
    return H, np.angle(mantissa)
