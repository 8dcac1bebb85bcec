"""Exact solution of a linear scene with dampers, harmonic/constant forces and gravity.

``M ẍ + C ẋ + K x = F0 + Σ_h (Fc_h cos Ω_h t + Fs_h sin Ω_h t)`` is solved in three parts, none of
which forms K or C in float64 (a small spring added to a large one rounds away; the sag of a
chain hanging from a 1e-9 N/m spring under 1e9 N/m ones came out 180× wrong that way):

1. **the static part** ``x_eq``: ``K x_eq = F0 − M a`` by the cancellation-free elimination of
   :mod:`numeric.exact.equilibrium` (``a`` the uniform acceleration of each free piece under its net
   load, zero on walled pieces);
2. **the modal basis** Φ, ω of the accurate spectrum (:mod:`numeric.modes.spectrum`, rigid modes exact
   by structure) and the damping in it, ``G = ΦᵀCΦ`` from the elements
   (:func:`numeric.modes.elements.modal_damping`);
3. **the dynamic part** ``x = x_eq + Φ q``: ``q̈ + G q̇ + Ω² q = Φᵀ(F(t) − F0) + Φᵀ M a``, made
   autonomous by adding the forcing's own oscillators as states (``ċ = -Ω s, ṡ = Ω c`` with
   ``c(0) = 1, s(0) = 0``, and ``u̇ = 0, u(0) = 1`` for the rigid pieces' constant force):

    z = (ω̂ q, q̇, c_1, s_1, …, u),   ż = A z,   z(t) = exp(A t) z(0),

   with ``ω̂ = ω`` for elastic modes and 1 for rigid ones, so every block of A has the size of its
   mode's ω (``[[0, ω], [−ω, −g]]``: balanced; in ``(q, q̇)`` the blocks ``[[0, 1], [−ω², 0]]`` of a
   stiff and a soft mode would make ``exp`` lose the soft one).

The matrix exponential contains the steady state and the transient at once,
and stays finite where closed forms divide by zero: exact resonance of an
undamped mode (a Jordan block gives the t·sin growth), critical damping, a
free piece accelerating under a constant force (½ a t²). It is evaluated at anchor
times ``exp(A t_i)`` every ``anchor`` samples and propagated between anchors
with ``exp(A h)``, so roundoff cannot accumulate over more than ``anchor`` products.

Ground motion given as a harmonic expression adds the force ``-m_i a_g(t)`` to every mass
through the same oscillator states. Tabulated inputs (forces, ground acceleration) are
piecewise linear in t, so the solution stays exact by **first-order hold**: with
``ż = A z + B u(t)`` and ``u`` linear on ``[a, b]`` (``u(a⁺)``, slope ``s``),

    exp(h [[A, B, 0], [0, 0, I], [0, 0, 0]]) (z(a), u(a⁺), s) = (z(b), …),   h = b − a,

stepped over the union of the output times and every table's rows (one exponential per
distinct interval length, lengths equal to 13 significant digits sharing one). A table is zero outside its rows, so it jumps at its ends when
its first or last value is not 0; ``u(a⁺)`` and ``u(b⁻)`` take the one-sided limits.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg

from ..system import System


#: Largest condition number of A's eigenvector matrix for which exp(A t) is taken from the
#: eigen-decomposition (otherwise scaling and squaring, scipy's expm).
EIG_COND = 1e3
#: ε·(g/ω)² of the most overdamped mode above which A's eigen-decomposition is done in mpmath.
STIFF_DAMPING = 1e-13
#: Largest state (2N + 2H + 1) decomposed in mpmath, and its working precision.
MP_MAX_STATES = 64
#: Largest state whose every eigenpair is refined (:func:`refine_small`): beside the slow ones, the
#: eigenvectors of weakly damped modes near the forcing's frequencies (2.9e-9 of the amplitude on a
#: 4-mass scene with gravity, a force and ground motion at 1e10 mass contrast; 1.4e-13 refined).
REFINE_ALL_STATES = 16
MP_DIGITS = 40
#: Most digits the change ``(exp(A t) − I) z0`` is carried to in mpmath (:meth:`AugmentedLinear._change_digits`).
MP_CHANGE_DIGITS = 1200
_EPS = float(np.finfo(float).eps)


def _phi(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``φ1(z) = (eᶻ − 1)/z`` and ``φ2(z) = (eᶻ − 1 − z)/z²`` (complex), by their series near 0."""
    small = np.abs(z) < 0.1
    zs = np.where(small, 0.0, z)
    with np.errstate(all="ignore"):
        p1 = np.where(small, 0.0, np.expm1(zs) / np.where(small, 1.0, zs))
        p2 = np.where(small, 0.0, (np.expm1(zs) - zs) / np.where(small, 1.0, zs * zs))
    # the series φ1 = Σ z^k/(k+1)!, φ2 = Σ z^k/(k+2)! (|z| < 0.1: 14 terms are far below ε)
    s1, s2 = np.zeros_like(z), np.zeros_like(z)
    fact1, fact2, zk = 1.0, 2.0, np.ones_like(z)
    for k in range(14):
        s1 = s1 + zk / fact1
        s2 = s2 + zk / fact2
        zk = zk * z
        fact1 *= k + 2
        fact2 *= k + 3
    return np.where(small, s1, p1), np.where(small, s2, p2)


#: A table row closer than SNAP·max|t| to an output time is taken at that time (rows read from
#: decimal text and times t = i·h differ by rounding; a kink moved by 1e-13 changes nothing).
SNAP = 1e-13


def refine_small(A: np.ndarray, lam: np.ndarray, V: np.ndarray, threshold: float = STIFF_DAMPING) -> tuple[np.ndarray, np.ndarray]:
    """Eigenpairs of A whose float64 eigenvalue errs by more than ``threshold`` of itself (LAPACK's
    error is ε·‖A‖, so these are the slow ones: |λ| < ε‖A‖/threshold; every pair for a negative
    threshold), refined by
    Newton's method on ``(A − λI) v = 0, e_kᵀ v = 1`` with the residual in extended precision
    (mpmath, :data:`MP_DIGITS` digits) and the correction solved in float64 (iterative refinement).

    A slow mode carrying a large initial offset (a scene released 2e7 m above the sag of a
    2e-6 N/m spring, ω_max/ω_min = 1e6) otherwise drifts by |q0|·ε‖A‖·t: 3e-9 of the amplitude.
    A pair whose iteration does not contract (a repeated eigenvalue) keeps its float64 value.

    A : ndarray, shape (S, S);  lam : ndarray, shape (S,);  V : ndarray, shape (S, S) (columns).
    """
    norm = float(np.max(np.sum(np.abs(A), axis=1)))
    slow = np.flatnonzero(_EPS * norm > threshold * np.abs(lam))
    if slow.size == 0:
        return lam, V
    import mpmath

    size = A.shape[0]
    # complex copies: LAPACK returns real arrays when every eigenvalue is real (a free mass with a
    # dashpot to the wall: λ = 0 and −c/m), and a refined pair is stored as complex
    lam, V = np.array(lam, dtype=complex), np.array(V, dtype=complex)
    with mpmath.workdps(MP_DIGITS):
        Am = mpmath.matrix(A.tolist())
        for j in slow:  # a loop over the few slow eigenpairs
            k = int(np.argmax(np.abs(V[:, j])))
            lm = mpmath.mpc(lam[j])
            vm = mpmath.matrix([mpmath.mpc(c / V[k, j]) for c in V[:, j]])
            last = np.inf
            for _ in range(6):
                r = Am * vm - lm * vm
                res = np.array([complex(r[i]) for i in range(size)])
                B = np.zeros((size + 1, size + 1), dtype=complex)
                B[:size, :size] = A - complex(lm) * np.eye(size)
                B[:size, size] = -np.array([complex(vm[i]) for i in range(size)])
                B[size, k] = 1.0
                with np.errstate(all="ignore"):
                    try:
                        step = np.linalg.solve(B, np.concatenate([-res, [0.0]]))
                    except np.linalg.LinAlgError:
                        break
                size_step = float(np.max(np.abs(step)))
                if not np.isfinite(size_step) or size_step > 0.5 * last:
                    break
                last = size_step
                for i in range(size):
                    vm[i] += mpmath.mpc(step[i])
                lm += mpmath.mpc(step[size])
                if size_step <= 1e-30 * max(1.0, float(abs(lm))):
                    break
            if np.isfinite(last) and abs(complex(lm) - lam[j]) <= 1e3 * _EPS * norm:
                scale = float(np.linalg.norm(V[:, j]))
                vec = np.array([complex(vm[i]) for i in range(size)])
                lam[j], V[:, j] = complex(lm), vec * (scale / np.linalg.norm(vec))
    return lam, V


@dataclass(frozen=True)
class AugmentedLinear:
    """The autonomous first-order system ``ż = A z`` of a linear scene, in its modal basis.

    A : ndarray, shape (2N + 2H + c, 2N + 2H + c)
        On ``z = (ω̂ q, q̇, oscillators, u)`` (module docstring).
    shapes : ndarray, shape (N, N)
        Φ, physical M-orthonormal modes as columns: ``x = x_eq + Φ q``, ``v = Φ q̇``.
    scale : ndarray, shape (N,)
        ω̂: ω of each elastic mode, 1 for a rigid one.
    x_eq : ndarray, shape (N,)
        The static part (:mod:`numeric.exact.equilibrium`).
    """

    A: np.ndarray = field(repr=False)
    n: int
    extra0: np.ndarray = field(repr=False)
    #: Piecewise-linear inputs ``(times (R,), values (R,), direction (N,))``: each adds
    #: ``direction · u(t)`` to the modal acceleration q̈ (first-order hold, see the module docstring).
    inputs: tuple = field(default=(), repr=False)
    shapes: np.ndarray = field(default=None, repr=False)
    scale: np.ndarray = field(default=None, repr=False)
    x_eq: np.ndarray = field(default=None, repr=False)
    masses: np.ndarray = field(default=None, repr=False)
    #: ω of each mode (0 for rigid ones) and the constant modal force on the rigid modes.
    omega: np.ndarray = field(default=None, repr=False)
    rigid_force: np.ndarray = field(default=None, repr=False)
    #: No damping and no harmonic forcing: every mode in closed form (:meth:`_closed_form`).
    modes_only: bool = False
    #: The static part in modal coordinates, shape (N,) (``x_eq = Φ q_eq``).
    q_eq: np.ndarray = field(default=None, repr=False)
    #: The constant load that deforms the springs, ``F0 − M a`` (a the free pieces' acceleration), shape (N,):
    #: ``K x_eq`` (the static spring forces follow from it by the load path, :mod:`numeric.structural.storeys`).
    static_load: np.ndarray = field(default=None, repr=False)

    @classmethod
    def from_system(cls, system: System) -> "AugmentedLinear":
        from ..modes.elements import Elements, modal_damping
        from .equilibrium import equilibrium
        from ..modes.spectrum import spectrum

        n = system.n
        m = system.masses
        el = Elements.from_system(system)
        spec = spectrum(m, system.spring_ends, system.stiffness)
        Phi, w = spec.shapes, spec.omega
        scale = np.where(w > 0, w, 1.0)
        G = modal_damping(el, w, Phi) if el.damped else None
        omegas, fc, fs = np.zeros(0), np.zeros((0, n)), np.zeros((0, n))
        loads = []  # constant forces, kept apart (their signs are summed separately)
        if system.has("gravity_forces"):
            loads.append(system.gravity_forces())
        if system.has("external_acceleration"):
            if not system.harmonic_forcing:
                raise ValueError("external forces are not constant + harmonic: no exact solution")
            omegas, fc, fs, c0 = system.forcing_harmonics()
            loads.append(c0)
        if system.ground == "expression":  # every mass feels -m_i a_g(t): acceleration -a_g(t)
            wg, gc, gs, g0 = system.ground_harmonics()
            omegas = np.concatenate([omegas, wg])
            fc = np.vstack([fc, -np.outer(gc, m)])
            fs = np.vstack([fs, -np.outer(gs, m)])
            loads.append(-g0 * m)
        static = equilibrium(m, system.spring_ends, system.stiffness, loads) if loads else None
        inputs = []
        for (tt, ff), on in zip(system.tables, system.provided.table_force_on):
            force = np.zeros(n)
            force[on] = 1.0
            inputs.append((tt, ff, Phi.T @ force))
        if system.ground == "table":
            inputs.append((system.ground_table[0], system.ground_table[1], -(Phi.T @ m)))
        h = omegas.shape[0]
        # the rigid pieces' constant force: exactly along the rigid modes (elastic ones are M-orthogonal)
        rigid_force = np.zeros(n)
        if static is not None and np.any(static.acceleration != 0):
            rigid_force[: spec.rigid] = Phi[:, : spec.rigid].T @ (m * static.acceleration)
        has_const = bool(np.any(rigid_force != 0))
        size = 2 * n + 2 * h + int(has_const)
        A = np.zeros((size, size))
        A[np.arange(n), n + np.arange(n)] = scale
        A[n + np.arange(n), np.arange(n)] = -w
        if G is not None:
            A[n:2 * n, n:2 * n] = -G
        for j in range(h):  # loop over forcing frequencies, not masses
            ci, si = 2 * n + 2 * j, 2 * n + 2 * j + 1
            A[n:2 * n, ci] = Phi.T @ fc[j]
            A[n:2 * n, si] = Phi.T @ fs[j]
            A[ci, si] = -omegas[j]
            A[si, ci] = omegas[j]
        if has_const:
            A[n:2 * n, -1] = rigid_force
        extra0 = np.zeros(size - 2 * n)
        extra0[0:2 * h:2] = 1.0
        if has_const:
            extra0[-1] = 1.0
        x_eq = static.x if static is not None else np.zeros(n)
        # the static part in modal coordinates: elastic φᵀF0/ω² (projecting a large x_eq instead would
        # leave ε·|M x_eq| in every stiff mode), rigid φᵀM x_eq (which no output depends on)
        q_eq = Phi.T @ (m * x_eq)
        if loads:
            F0 = np.sum(loads, axis=0)
            el_ = w > 0
            q_eq[el_] = (Phi[:, el_].T @ F0) / (w[el_] * w[el_])
        static_load = (np.sum(loads, axis=0) - m * static.acceleration) if loads else np.zeros(n)
        return cls(A, n, extra0, tuple(inputs), Phi, scale, x_eq, m, w, rigid_force, G is None and h == 0, q_eq,
                   static_load)

    def _initial(self, x0: np.ndarray, v0: np.ndarray) -> np.ndarray:
        """``z(0)`` (modal: ``ω̂ (q0 − q_eq)``, ``q̇0``, oscillators, u) from physical ``x0``, ``v0`` (shape (N,))."""
        Mphi = self.masses[:, None] * self.shapes
        q0 = Mphi.T @ np.asarray(x0, dtype=float) - self.q_eq
        return np.concatenate([self.scale * q0, Mphi.T @ np.asarray(v0, dtype=float), self.extra0])

    def _physical(self, Z: np.ndarray, D: np.ndarray, x0: np.ndarray, v0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x, v (S, N) from the states ``Z = z(t)`` and their changes ``D = z(t) − z(0)`` (S, size).

        Two exact forms: ``x = x_eq + Φ y`` (about the equilibrium) and ``x = x0 + Φ Δy`` (the change from
        the start), where y = q − q_eq. Each frame takes the one with the smaller rounding
        (ε·(|x_eq| + |Φ||y|) against ε·(|x0| + |Φ||Δy|)): a scene released far from its equilibrium
        (a soft spring's sag of 4e7 m, 490 m fallen after 10 s) is then not the small difference of the
        static part and the oscillation about it, and a damped one settles on x_eq itself.
        """
        n = self.n
        x0 = np.asarray(x0, dtype=float)
        v0 = np.asarray(v0, dtype=float)
        Phi, aPhi = self.shapes, np.abs(self.shapes)
        y, dy = Z[:, :n] / self.scale[None, :], D[:, :n] / self.scale[None, :]
        about = np.max(np.abs(self.x_eq)[None, :] + np.abs(y) @ aPhi.T, axis=1)
        change = np.max(np.abs(x0)[None, :] + np.abs(dy) @ aPhi.T, axis=1)
        use = (about < change)[:, None]
        x = np.where(use, self.x_eq[None, :] + y @ Phi.T, x0[None, :] + dy @ Phi.T)
        vd, vc = Z[:, n:2 * n], D[:, n:2 * n]
        about_v = np.max(np.abs(vd) @ aPhi.T, axis=1)
        change_v = np.max(np.abs(v0)[None, :] + np.abs(vc) @ aPhi.T, axis=1)
        v = np.where((about_v < change_v)[:, None], vd @ Phi.T, v0[None, :] + vc @ Phi.T)
        return x, v

    def _closed_form(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The states ``(Z, D)`` (S, size) when there is no damping and no harmonic forcing (constant loads
        only): each mode in closed form,

            y = y0 cos ωt + ẏ0 · t·sinc(ωt) + f t²/2,
            Δy = −2 y0 sin²(ωt/2) + ẏ0 · t·sinc(ωt) + f t²/2   (and their rates),

        with ``f`` the constant force on a rigid mode (0 on elastic ones: the static part took it),
        never dividing by ω and without the error that ``exp(A t)`` accumulates when ω_max·t is
        large (1.2e-9 of the amplitude against 1.3e-13 on a hanging chain at ω_max·t = 1.4e9).
        """
        from .special import tsinc

        n = self.n
        z0 = self._initial(x0, v0)
        y0, p0 = z0[:n] / self.scale, z0[n:2 * n]
        w, f = self.omega[None, :], self.rigid_force[None, :]
        tt = t[:, None]
        half = np.sin(0.5 * w * tt)
        c1 = -2.0 * half * half  # cos(ωt) − 1 without cancellation
        c = np.cos(w * tt)
        ts = tsinc(w, tt)
        ramp, drift = 0.5 * f * tt * tt, f * tt
        Z = np.concatenate([(y0 * c + p0 * ts + ramp) * self.scale, p0 * c - (w * w) * y0 * ts + drift], axis=1)
        D = np.concatenate([(y0 * c1 + p0 * ts + ramp) * self.scale, p0 * c1 - (w * w) * y0 * ts + drift], axis=1)
        return Z, D

    @cached_property
    def _eigen(self):
        """``(λ, V, V⁻¹)`` of A when its eigenvector matrix is well conditioned (cond ≤ :data:`EIG_COND`),
        else None. ``exp(A t) = V exp(Λt) V⁻¹`` then errs by ~ε·cond(V) whatever ‖A t‖, where scaling and
        squaring errs by ε·‖A t‖ — 8e-10 on a scene with dashpots of 1e6 N·s/m on 2e-6 kg masses
        (‖A h‖ = 3e7), while the decomposition errs by 4e-13 (cond(V) = 1.2).

        An overdamped mode whose dashpots exceed its ω by a factor g/ω has a slow rate ω²/g that a
        float64 eigensolver gets only to ε·(g/ω)² (the small root of λ² + gλ + ω²); when that exceeds
        :data:`STIFF_DAMPING`, λ and V come from mpmath (:data:`MP_DIGITS` digits) for systems of at most
        :data:`MP_MAX_STATES` states, then are rounded: the exponential of the float64 A, to float64.
        """
        Ab, d = self._balanced
        lam, V = np.linalg.eig(Ab)
        cond = np.linalg.cond(V)
        if not np.isfinite(cond) or cond > EIG_COND:
            return None
        V = d[:, None] * V  # eigenvectors of A = D Ab D⁻¹ (powers of 2: exact)
        n = self.n
        g = np.abs(np.diag(self.A[n:2 * n, n:2 * n]))
        w = np.abs(np.diag(self.A[n:2 * n, :n]))
        stiff = np.max(np.where(w > 0, (g / np.where(w > 0, w, 1.0)) ** 2, 0.0), initial=0.0) * _EPS
        if stiff > STIFF_DAMPING and self.A.shape[0] <= MP_MAX_STATES:
            import mpmath

            size = self.A.shape[0]
            with mpmath.workdps(MP_DIGITS):
                lm, Vm = mpmath.eig(mpmath.matrix(self.A.tolist()))
                Wm = mpmath.inverse(Vm)
                lam = np.array([complex(v) for v in lm])
                V = np.array([[complex(Vm[i, j]) for j in range(size)] for i in range(size)])
                return lam, V, np.array([[complex(Wm[i, j]) for j in range(size)] for i in range(size)])
        if self.A.shape[0] <= MP_MAX_STATES:  # every pair of a small state, the slow ones up to MP_MAX_STATES
            lam, V = refine_small(self.A, lam, V, -1.0 if self.A.shape[0] <= REFINE_ALL_STATES else STIFF_DAMPING)
        return lam, V, np.linalg.inv(V)

    @cached_property
    def _balanced(self) -> tuple[np.ndarray, np.ndarray]:
        """``(D⁻¹ A D, diag D)``, D a diagonal of powers of 2 (LAPACK's balancing): the forcing's
        oscillator states and the modes can differ in scale by 1e7 (a drive near a soft mode)."""
        Ab, (scale, _) = scipy.linalg.matrix_balance(self.A, permute=False, separate=True)
        return Ab, scale

    def _flow(self, t: float, z0: np.ndarray, B: np.ndarray | None = None) -> tuple:
        """``(exp(A t), (exp(A t) − I) z0)`` and, with inputs B (size, m), the first-order-hold terms
        ``(t φ1(A t) B, t² φ2(A t) B)``. The change is ``V expm1(Λt) V⁻¹ z0`` (or the last column of
        ``exp([[A, A z0], [0, 0]] t)``): accurate to the size of the change, not of z."""
        eig = self._eigen
        if eig is not None:
            lam, V, W = eig
            z = lam * t
            e, e1 = np.exp(z), np.expm1(z)
            E = ((V * e[None, :]) @ W).real
            d = (V @ (e1 * (W @ z0))).real
            if B is None:
                return E, d
            p1, p2 = _phi(z)
            WB = W @ B
            return E, d, (V @ ((t * p1)[:, None] * WB)).real, (V @ ((t * t * p2)[:, None] * WB)).real
        size = self.A.shape[0]
        Ab, sc = self._balanced  # exp(A t) = D exp(Ab t) D⁻¹
        m = 0 if B is None else B.shape[1]
        k = size + 2 * m
        big = np.zeros((k + 1, k + 1))
        big[:size, :size] = Ab
        if m:
            big[:size, size:size + m] = B / sc[:, None]
            big[size:size + m, size + m:k] = np.eye(m)
        big[:size, k] = Ab @ (z0 / sc)
        F = scipy.linalg.expm(big * t)
        E = sc[:, None] * F[:size, :size] / sc[None, :]
        if B is None:
            return E, sc * F[:size, k]
        return E, sc * F[:size, k], sc[:, None] * F[:size, size:size + m], sc[:, None] * F[:size, size + m:k]

    def solve(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray, h: float | None = None,
              anchor: int = 64) -> tuple[np.ndarray, np.ndarray]:
        """x, v at times ``t`` (shape (S,)) from x0, v0 (shape (N,)); returns (S, N) arrays
        (:meth:`states`, then the physical coordinates)."""
        return self._physical(*self.states(x0, v0, t, h, anchor), x0, v0)

    def solve_grid(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`solve` on a simulation's grid (uniform, possibly with a shorter last interval)."""
        return self._physical(*self.states_grid(x0, v0, t), x0, v0)

    def states_grid(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`states` on a simulation's grid: the uniform part propagated between anchors, a shorter
        last interval on its own."""
        t = np.asarray(t, dtype=float)
        if self.inputs:  # stepped over the union of t and the tables' rows from t = 0: any grid at once
            return self.states(x0, v0, t)
        if t.shape[0] < 3 or abs((t[-1] - t[-2]) - (t[1] - t[0])) <= 1e-12 * abs(t[1] - t[0]):
            return self.states(x0, v0, t, float(t[1] - t[0]) if t.shape[0] > 1 else None)
        Z, D = self.states(x0, v0, t[:-1], float(t[1] - t[0]))
        Zl, Dl = self.states(x0, v0, t[-1:], None)
        return np.concatenate([Z, Zl]), np.concatenate([D, Dl])

    def modal_coordinates(self, Z: np.ndarray) -> np.ndarray:
        """``y = q − q_eq`` (S, N) of states Z (:meth:`states`): ``x = x_eq + Φ y``."""
        return Z[:, :self.n] / self.scale[None, :]

    def states(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray, h: float | None = None,
               anchor: int = 64) -> tuple[np.ndarray, np.ndarray]:
        """The states ``Z = z(t)`` and their changes ``D = z(t) − z(0)`` (S, size) at times ``t`` (S,) from
        x0, v0 (N,) (the modal coordinates: :meth:`modal_coordinates`; x and v: :meth:`solve`).

        The state and its change ``z(t) − z(0)`` are both propagated (:meth:`_physical`). If the
        times are a uniform grid ``t = i·h`` pass ``h`` to propagate between anchors,
        ``z(t + h) = exp(A h) z(t)`` and ``Δ(t + h) = exp(A h) Δ(t) + (exp(A h) − I) z0``; otherwise
        each time gets its own exponential.
        """
        if self.inputs:
            return self._solve_inputs(x0, v0, np.asarray(t, dtype=float))
        t = np.asarray(t, dtype=float)
        if self.modes_only:
            return self._closed_form(x0, v0, t)
        z0 = self._initial(x0, v0)
        size = z0.shape[0]
        Z = np.empty((t.shape[0], size))
        D = np.empty((t.shape[0], size))
        digits = self._change_digits(z0, x0, v0, t, h)
        flow = self._flow if digits is None else (lambda ti, z: self._flow_mp(ti, z, digits))
        if h is None:
            for i, ti in enumerate(t):
                E, d = flow(ti, z0)
                Z[i], D[i] = E @ z0, d
        else:
            Eh, dh = flow(h, z0)
            for i0 in range(0, t.shape[0], anchor):
                E, d = flow(t[i0], z0)
                z = E @ z0
                Z[i0], D[i0] = z, d
                for i in range(i0 + 1, min(i0 + anchor, t.shape[0])):
                    z, d = Eh @ z, Eh @ d + dh
                    Z[i], D[i] = z, d
        return Z, D

    def _change_digits(self, z0: np.ndarray, x0: np.ndarray, v0: np.ndarray, t: np.ndarray,
                       h: float | None) -> int | None:
        """Working digits for the change ``(exp(A t) − I) z0`` in mpmath (:meth:`_flow_mp`), or None where
        float64 (:meth:`_flow`) holds it to 1e-12 of the motion.

        float64 errs by about ε·‖z0‖ in every component of the change (the eigenvectors, or scaling and
        squaring, mix the components); a mode's position is that over its ω̂. A scene released far from
        its equilibrium on a slow mode (a 1e60 kg mass on a 1e-100 N/m spring, damped: sag 1e161 m,
        ω = 1e-80/s) has ‖z0‖/ω̂ = 1e161 m where it moves by centimetres: the change must be carried to
        that many more digits. The motion's scale is the larger of |x0| and the first sample's
        |v0| t + |a0| t²/2 (a0 the initial acceleration). Small states only (:data:`MP_MAX_STATES`)."""
        n = self.n
        size = z0.shape[0]
        if size > MP_MAX_STATES or t.shape[0] == 0:
            return None
        aphi = np.abs(self.shapes)
        eig = self._eigen
        if eig is not None:  # V expm1(Λt) V⁻¹ z0: each component errs by ε |V| |V⁻¹ z0| (decoupled modes apart)
            lam, V, W = eig
            err = 4 * _EPS * (np.abs(V) @ (np.abs(W) @ np.abs(z0)))
        else:
            err = np.full(size, _EPS * float(np.max(np.abs(z0))))
        reach = float(np.max(aphi @ (err[:n] / self.scale), initial=0.0))
        if reach == 0.0 or not np.isfinite(reach):
            return None
        first = float(h) if h is not None else float(np.min(np.abs(t[t != 0]), initial=0.0))
        acc = self.A[n:2 * n] @ z0  # modal acceleration q̈(0)
        motion = max(float(np.max(np.abs(x0), initial=0.0)),
                     float(np.max(aphi @ (np.abs(z0[n:2 * n]) * first + np.abs(acc) * first * first / 2), initial=0.0)))
        if not motion > 0 or reach <= 1e-12 * motion:
            return None
        digits = 30 + int(np.ceil(np.log10(reach / (_EPS * motion))))
        return digits if digits <= MP_CHANGE_DIGITS else None

    def _flow_mp(self, t: float, z0: np.ndarray, digits: int) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_flow` with the change ``(exp(A t) − I) z0`` from mpmath's expm at ``digits`` digits (A, z0
        and t taken exactly as the float64 values they are), then rounded: accurate to the size of each
        component of the change, where float64 is accurate to ‖z0‖ only."""
        import mpmath

        size = z0.shape[0]
        with mpmath.workdps(digits):
            Et = mpmath.expm(mpmath.matrix(self.A.tolist()) * mpmath.mpf(float(t)))
            zm = [mpmath.mpf(float(v)) for v in z0]
            d = np.array([float(mpmath.fsum((Et[i, j] - (1 if i == j else 0)) * zm[j] for j in range(size)))
                          for i in range(size)])
            E = np.array([[float(Et[i, j]) for j in range(size)] for i in range(size)])
        return E, d

    def _input_values(self, a: float, b: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
        """One-sided limits ``u(a⁺)`` and ``u(b⁻)`` of every input, shape (m,) each."""
        right, left = [], []
        for tt, yy, _ in self.inputs:
            t0, t1 = float(tt[0]), float(tt[-1])
            # a row within tol of a or b was snapped onto it: the limits are taken at the row
            inside_a = t0 - tol <= a < t1 - tol
            inside_b = t0 + tol < b <= t1 + tol
            right.append(float(np.interp(min(max(a, t0), t1), tt, yy)) if inside_a else 0.0)
            left.append(float(np.interp(min(max(b, t0), t1), tt, yy)) if inside_b else 0.0)
        return np.array(right), np.array(left)

    def _solve_inputs(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The states ``(Z, D)`` at ``t`` (times ≥ 0, ascending) of the first-order-hold solution on the
        union of 0, ``t`` and the tables' rows (see module docstring): stepped from the initial state at
        t = 0 whatever the first requested time."""
        size, m = self.A.shape[0], len(self.inputs)
        z0 = self._initial(x0, v0)
        B = np.zeros((size, m))
        for j, (_, _, direction) in enumerate(self.inputs):
            B[self.n:2 * self.n, j] = direction
        tol = SNAP * max(1.0, float(np.max(np.abs(t))))
        times = np.union1d([0.0], t)  # the initial state is at t = 0
        knots = np.concatenate([tt for tt, _, _ in self.inputs])
        knots = knots[(knots > times[0]) & (knots < times[-1])]
        near = np.clip(np.searchsorted(times, knots), 1, max(times.shape[0] - 1, 1))
        gap = np.minimum(np.abs(knots - times[near - 1]), np.abs(times[np.minimum(near, times.shape[0] - 1)] - knots))
        grid = np.union1d(times, knots[gap > tol])  # a row within rounding of an output time is that time
        out = np.searchsorted(grid, t)  # rows of grid that are output times
        flows: dict[float, np.ndarray] = {}
        Z = np.empty((grid.shape[0], size))  # the state and its change z − z(0) (see _physical)
        D = np.empty((grid.shape[0], size))
        Z[0], D[0] = z0, 0.0
        for i in range(grid.shape[0] - 1):  # loop over time intervals, not masses
            a, b = float(grid[i]), float(grid[i + 1])
            h = b - a
            key = float(f"{h:.13e}")  # t = i·h grids differ from h by rounding: one exponential
            F = flows.get(key)
            if F is None:
                F = flows[key] = self._flow(key, z0, B)
            E, d, hold, ramp = F
            ua, ub = self._input_values(a, b, tol)
            forced = hold @ ua + ramp @ ((ub - ua) / h)
            Z[i + 1] = E @ Z[i] + forced
            D[i + 1] = E @ D[i] + d + forced
        return Z[out], D[out]


def frequency_response(system: System, drive: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Complex amplitudes X(Ω) = (K − Ω²M + iΩC)⁻¹ F for each drive frequency.

    Parameters
    ----------
    drive : ndarray, shape (W,)
    force : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (W, N), complex (inf where an undamped mode is hit exactly)
    """
    K = system.stiffness_matrix()
    M = np.diag(system.masses)
    C = system.damping_matrix() if system.damped else 0 * K
    Z = K[None] - (drive**2)[:, None, None] * M[None] + 1j * drive[:, None, None] * C[None]
    with np.errstate(all="ignore"):
        return np.linalg.solve(Z, np.broadcast_to(force.astype(complex), (drive.shape[0], force.shape[0]))[..., None])[..., 0]
