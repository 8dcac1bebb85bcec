"""Exact solution of a linear scene with dampers, harmonic/constant forces and gravity.

``M ẍ + C ẋ + K x = F0 + Σ_h (Fc_h cos Ω_h t + Fs_h sin Ω_h t)`` is made autonomous
by adding the forcing's own oscillators as states (``ċ = -Ω s, ṡ = Ω c`` with
``c(0) = 1, s(0) = 0``, and ``u̇ = 0, u(0) = 1`` for the constant part):

    z = (x, v, c_1, s_1, …, u),   ż = A z,   z(t) = exp(A t) z(0).

The matrix exponential contains the steady state and the transient at once,
and stays finite where closed forms divide by zero: exact resonance of an
undamped mode (a Jordan block gives the t·sin growth), critical damping, a
free piece accelerating under gravity (½ g t²). It is evaluated at anchor
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

import numpy as np
import scipy.linalg

from .system import System


#: A table row closer than SNAP·max|t| to an output time is taken at that time (rows read from
#: decimal text and times t = i·h differ by rounding; a kink moved by 1e-13 changes nothing).
SNAP = 1e-13


@dataclass(frozen=True)
class AugmentedLinear:
    """The autonomous first-order system ``ż = A z`` of a linear scene.

    A : ndarray, shape (2N + 2H + c, 2N + 2H + c)
    """

    A: np.ndarray = field(repr=False)
    n: int
    extra0: np.ndarray = field(repr=False)
    #: Piecewise-linear inputs ``(times (R,), values (R,), direction (N,))``: each adds
    #: ``direction · u(t)`` to the acceleration (first-order hold, see the module docstring).
    inputs: tuple = field(default=(), repr=False)

    @classmethod
    def from_system(cls, system: System) -> "AugmentedLinear":
        mod, p = system.module, system.params
        n = system.n
        minv = 1.0 / system.masses
        K = np.asarray(mod.stiffness_matrix(**p), dtype=float)
        C = np.asarray(mod.damping_matrix(**p), dtype=float) if system.damped else None
        omegas, fc, fs = np.zeros(0), np.zeros((0, n)), np.zeros((0, n))
        const = np.zeros(n)
        if system.has("gravity_forces"):
            const = const + np.asarray(mod.gravity_forces(**p), dtype=float)
        if system.has("external_acceleration"):
            if not system.harmonic_forcing:
                raise ValueError("external forces are not constant + harmonic: no exact solution")
            omegas, fc, fs, c0 = (np.asarray(a, dtype=float) for a in mod.forcing_harmonics(**p))
            const = const + c0
        if system.ground == "expression":  # every mass feels -m_i a_g(t): acceleration -a_g(t)
            wg, gc, gs, g0 = mod.ground_harmonics(**p)
            wg = np.asarray(wg, dtype=float)
            omegas = np.concatenate([omegas, wg])
            fc = np.vstack([fc, -np.outer(np.asarray(gc, dtype=float), system.masses)])
            fs = np.vstack([fs, -np.outer(np.asarray(gs, dtype=float), system.masses)])
            const = const - float(g0) * system.masses
        inputs = []
        for (tt, ff), on in zip(system.tables, system.provided.table_force_on):
            direction = np.zeros(n)
            direction[on] = minv[on]
            inputs.append((tt, ff, direction))
        if system.ground == "table":
            inputs.append((system.ground_table[0], system.ground_table[1], -np.ones(n)))
        h = omegas.shape[0]
        has_const = bool(np.any(const != 0))
        size = 2 * n + 2 * h + int(has_const)
        A = np.zeros((size, size))
        A[:n, n:2 * n] = np.eye(n)
        A[n:2 * n, :n] = -minv[:, None] * K
        if C is not None:
            A[n:2 * n, n:2 * n] = -minv[:, None] * C
        for j in range(h):  # loop over forcing frequencies, not masses
            ci, si = 2 * n + 2 * j, 2 * n + 2 * j + 1
            A[n:2 * n, ci] = minv * fc[j]
            A[n:2 * n, si] = minv * fs[j]
            A[ci, si] = -omegas[j]
            A[si, ci] = omegas[j]
        if has_const:
            A[n:2 * n, -1] = minv * const
        extra0 = np.zeros(size - 2 * n)
        extra0[0:2 * h:2] = 1.0
        if has_const:
            extra0[-1] = 1.0
        return cls(A, n, extra0, tuple(inputs))

    def solve(self, x0: np.ndarray, v0: np.ndarray, t: np.ndarray, h: float | None = None,
              anchor: int = 64) -> tuple[np.ndarray, np.ndarray]:
        """x, v at times ``t`` (shape (S,)) from x0, v0 (shape (N,)); returns (S, N) arrays.

        If the times are a uniform grid ``t = i·h`` pass ``h`` to propagate
        between anchors with ``exp(A h)``; otherwise each time gets its own exponential.
        """
        if self.inputs:
            return self._solve_inputs(x0, v0, np.asarray(t, dtype=float))
        z0 = np.concatenate([x0, v0, self.extra0])
        t = np.asarray(t, dtype=float)
        Z = np.empty((t.shape[0], z0.shape[0]))
        if h is None:
            for i, ti in enumerate(t):
                Z[i] = scipy.linalg.expm(self.A * ti) @ z0
        else:
            Eh = scipy.linalg.expm(self.A * h)
            for i0 in range(0, t.shape[0], anchor):
                z = scipy.linalg.expm(self.A * t[i0]) @ z0
                Z[i0] = z
                for i in range(i0 + 1, min(i0 + anchor, t.shape[0])):
                    z = Eh @ z
                    Z[i] = z
        return Z[:, :self.n], Z[:, self.n:2 * self.n]


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
        """First-order-hold solution on the union of ``t`` and the tables' rows (see module docstring)."""
        size, m = self.A.shape[0], len(self.inputs)
        B = np.zeros((size, m))
        for j, (_, _, direction) in enumerate(self.inputs):
            B[self.n:2 * self.n, j] = direction
        big = np.zeros((size + 2 * m, size + 2 * m))
        big[:size, :size] = self.A
        big[:size, size:size + m] = B
        big[size:size + m, size + m:] = np.eye(m)
        tol = SNAP * max(1.0, float(np.max(np.abs(t))))
        knots = np.concatenate([tt for tt, _, _ in self.inputs])
        knots = knots[(knots > t[0]) & (knots < t[-1])]
        near = np.clip(np.searchsorted(t, knots), 1, t.shape[0] - 1)
        gap = np.minimum(np.abs(knots - t[near - 1]), np.abs(t[near] - knots))
        grid = np.union1d(t, knots[gap > tol])  # a row within rounding of an output time is that time
        out = np.searchsorted(grid, t)  # rows of grid that are output times
        flows: dict[float, np.ndarray] = {}
        Z = np.empty((grid.shape[0], size))
        Z[0] = np.concatenate([x0, v0, self.extra0])
        for i in range(grid.shape[0] - 1):  # loop over time intervals, not masses
            a, b = float(grid[i]), float(grid[i + 1])
            h = b - a
            key = float(f"{h:.13e}")  # t = i·h grids differ from h by rounding: one exponential
            E = flows.get(key)
            if E is None:
                E = flows[key] = scipy.linalg.expm(big * key)[:size]
            ua, ub = self._input_values(a, b, tol)
            Z[i + 1] = E[:, :size] @ Z[i] + E[:, size:size + m] @ ua + E[:, size + m:] @ ((ub - ua) / h)
        Z = Z[out]
        return Z[:, :self.n], Z[:, self.n:2 * self.n]


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
    mod, p = system.module, system.params
    K = np.asarray(mod.stiffness_matrix(**p), dtype=float)
    M = np.diag(system.masses)
    C = np.asarray(mod.damping_matrix(**p), dtype=float) if system.damped else 0 * K
    Z = K[None] - (drive**2)[:, None, None] * M[None] + 1j * drive[:, None, None] * C[None]
    with np.errstate(all="ignore"):
        return np.linalg.solve(Z, np.broadcast_to(force.astype(complex), (drive.shape[0], force.shape[0]))[..., None])[..., 0]
