"""Reference solutions for the benchmark: the exact modal solution in extended precision
(:class:`ExtendedModalReference`) and a grid reference for scenes without one (:class:`GridReference`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..io.array_record import array_record
from ..run import registry
from ..run.grid import Grid
from ..run.protocol import Options, Recorded
from ..run.protocol import record
from ..system import System


# -- references ----------------------------------------------------------------------------------
@array_record
class ExtendedModalReference:
    """The exact solution of an undamped linear chain in extended precision.

    The eigen-decomposition of ``D = M^-1/2 K M^-1/2`` is done by ``mpmath`` at
    40 digits from the float64 parameters (so it is exact for the problem the
    methods solve); ω, the shapes and the modal initial values are kept as
    ``numpy.longdouble`` (64-bit mantissa on x86-64) and the solution is
    evaluated in that precision: phase errors ``ω t ε_ld`` stay below 1e-16
    up to ``t ≈ 10⁴`` and below 1e-13 at ``t = 10⁶``. Rigid modes (zero
    eigenvalues, by structure) follow ``q0 + q̇0 t``.

    Attributes
    ----------
    omega : ndarray of longdouble, shape (N,)
    shapes : ndarray of longdouble, shape (N, N)
        ``M^-1/2 E``.
    q0, p0 : ndarray of longdouble, shape (N,)
    description : str
    """

    omega: np.ndarray
    shapes: np.ndarray
    q0: np.ndarray
    p0: np.ndarray
    description: str = ""

    @classmethod
    def from_system(cls, system: System, x0: np.ndarray, v0: np.ndarray, digits: int = 40,
                    max_n: int = 40) -> "ExtendedModalReference":
        """Build from the system's masses and springs; above ``max_n`` masses fall back to float64 modes."""
        ld = np.longdouble
        n = system.n
        if n > max_n:
            spec = system.spectrum
            r = np.sqrt(spec.masses)
            E = spec.vectors
            return cls(spec.omega.astype(ld), (E / r[:, None]).astype(ld), (E.T @ (r * x0)).astype(ld),
                       (E.T @ (r * v0)).astype(ld), "modal solution, float64 spectrum (N too large for mpmath)")
        import mpmath

        with mpmath.workdps(digits):
            K = mpmath.zeros(n, n)
            for (a, b), k in zip(system.spring_ends.tolist(), system.stiffness.tolist()):
                k = mpmath.mpf(k)
                for i in (a, b):
                    if i >= 0:
                        K[i, i] += k
                if a >= 0 and b >= 0 and a != b:
                    K[a, b] -= k
                    K[b, a] -= k
            r = [mpmath.sqrt(mpmath.mpf(m)) for m in system.masses.tolist()]
            D = mpmath.matrix(n, n)
            for i in range(n):
                for j in range(n):
                    D[i, j] = K[i, j] / (r[i] * r[j])
            lam, E = mpmath.eigsy(D)
            scale = max(abs(x) for x in lam) if n else 1
            x0m = [mpmath.mpf(v) for v in np.asarray(x0, dtype=float).tolist()]
            v0m = [mpmath.mpf(v) for v in np.asarray(v0, dtype=float).tolist()]

            def to_ld(x):
                hi = float(x)
                return ld(hi) + ld(float(x - hi))

            omega = np.array([to_ld(mpmath.sqrt(l_)) if l_ > mpmath.mpf(10) ** (-25) * scale else ld(0)
                              for l_ in lam], dtype=ld)
            shapes = np.array([[to_ld(E[i, j] / r[i]) for j in range(n)] for i in range(n)], dtype=ld)
            q0 = np.array([to_ld(mpmath.fsum(E[i, j] * r[i] * x0m[i] for i in range(n))) for j in range(n)],
                          dtype=ld)
            p0 = np.array([to_ld(mpmath.fsum(E[i, j] * r[i] * v0m[i] for i in range(n))) for j in range(n)],
                          dtype=ld)
        return cls(omega, shapes, q0, p0, f"modal solution: mpmath eigen-decomposition ({digits} digits), "
                                          "evaluated in 80-bit extended precision")

    def at(self, t: np.ndarray, chunk: int = 1 << 16) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at times ``t`` (S,), as float64 arrays of shape (S, N)."""
        t = np.asarray(t, dtype=float)
        xs = np.empty((t.shape[0], self.shapes.shape[0]))
        vs = np.empty_like(xs)
        w = self.omega
        rigid = w == 0
        wsafe = np.where(rigid, np.longdouble(1), w)
        for lo in range(0, t.shape[0], chunk):
            tt = t[lo:lo + chunk].astype(np.longdouble)[:, None]
            ph = tt * w[None, :]
            c, s = np.cos(ph), np.sin(ph)
            q = self.q0 * c + np.where(rigid, self.p0 * tt, self.p0 * s / wsafe)
            p = np.where(rigid, self.p0, -self.q0 * wsafe * s + self.p0 * c)
            xs[lo:lo + chunk] = (q @ self.shapes.T).astype(float)
            vs[lo:lo + chunk] = (p @ self.shapes.T).astype(float)
        return xs, vs


@dataclass(frozen=True)
class GridReference:
    """A reference trajectory on a grid, for scenes without an exact solution.

    Attributes
    ----------
    run : Recorded
        The reference run: ``t`` (S,), ``x``, ``v`` (S, N).
    accuracy : float
        Estimated largest position error of the reference itself.
    description : str
    """

    run: Recorded = field(repr=False)
    accuracy: float
    description: str

    @property
    def x(self) -> np.ndarray:
        """Positions, shape (S, N)."""
        return self.run.x

    @classmethod
    def kahan_li(cls, system: System, x0, v0, t_end: float, spacing: float, m_fine: int, m_coarse: int,
                 progress: Callable[[str], None] | None = None) -> "GridReference":
        """The reference step method (Kahan–Li 8, eighth order) with steps ``spacing/m_fine``; its
        error ≈ difference from ``spacing/m_coarse`` times ``r⁸/(1 − r⁸)``, ``r = m_coarse/m_fine``."""
        method = registry.method(registry.REFERENCE_STEP, Options(progress=False))
        p = method.traits.order
        n = int(round(t_end / spacing))
        if progress:
            progress(f"reference: {method.name} at h = {spacing / m_fine:.4g} over t = {t_end:g}")
        fine = record(method, system, x0, v0, Grid(spacing / m_fine, n * m_fine, m_fine))
        coarse = record(method, system, x0, v0, Grid(spacing / m_coarse, n * m_coarse, m_coarse))
        rp = (m_coarse / m_fine) ** p
        diff = float(np.max(np.abs(fine.x - coarse.x)))
        acc = diff * rp / (1 - rp)
        return cls(fine, acc,
                   f"{method.name} at h = {spacing / m_fine:.4g} (estimated error {acc:.1e} from a second run at "
                   f"h = {spacing / m_coarse:.4g})")

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at grid times ``t``, shapes (S, N)."""
        run = self.run
        idx = np.rint(np.asarray(t) / (run.t[1] - run.t[0])).astype(int)
        return run.x[idx], run.v[idx]
