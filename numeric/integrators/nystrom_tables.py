"""Embedded Runge–Kutta–Nyström tables for ``ẍ = f(t, x)`` as frozen, self-checking data.

One step of an ``s``-stage RKN pair from ``(x, v)`` with step ``h``::

    k_i    = f(t + c_i h,  x + c_i h v + h² Σ_j a_ij k_j)        (j < i)
    x_new  = x + h v + h² Σ_i b_i  k_i
    v_new  = v +       h Σ_i b'_i k_i

and the embedded (lower-order) solution uses ``b̂``, ``b̂'`` instead. The entries are exact:
rationals as :class:`fractions.Fraction`, and surds ``p + q·√d`` (Dormand–Prince RKN6(4))
as :class:`Surd`; the checks run in 50-digit :mod:`mpmath` arithmetic and the floats the
integrator uses are correctly rounded from those values.

When a table is built it checks (raising :class:`ValueError` naming the table), to ``TOL``:

* the row sums ``Σ_j a_ij = c_i²/2`` (each stage consistent with ``x + c h v``);
* ``Σ b = 1/2`` and ``Σ b' = 1`` for the method and for the embedded pair;
* the quadrature conditions ``Σ b'_i c_i^k = 1/(k+1)`` (``k < p``) and
  ``Σ b_i c_i^k = 1/((k+1)(k+2))`` (``k ≤ p − 2``), at order ``p`` of the method and at the
  embedded order;
* the conditions of the trees with one nested stage sum,
  ``Σ b'_i c_i^k (A c^m)_i = 1/((m+1)(m+2)(k+m+3))`` for ``k + m + 3 ≤ p`` and
  ``Σ b_i c_i^k (A c^m)_i = 1/((m+1)(m+2)(k+m+3)(k+m+4))`` for ``k + m + 4 ≤ p``
  (from ``∫₀^{c}(c − s) s^m ds``);
* that the declared order is not exceeded by accident: the first quadrature condition
  beyond ``p`` fails;
* the first-same-as-last property when declared (last stage row = ``b``, ``c_s = 1``).

The full order (every Nyström tree) is verified by the convergence-slope tests.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property

import mpmath
import numpy as np

#: Tolerance of the identities (exact data: checked in 50-digit arithmetic).
TOL = 1e-14
#: Working precision of the checks, in decimal digits.
DIGITS = 50


@dataclass(frozen=True)
class Surd:
    """The number ``p + q·√d`` (``p``, ``q`` rational, ``d`` a positive integer)."""

    p: Fraction
    q: Fraction
    d: int

    def mpf(self) -> mpmath.mpf:
        return mpmath.mpf(self.p.numerator) / self.p.denominator + \
            mpmath.mpf(self.q.numerator) / self.q.denominator * mpmath.sqrt(self.d)


def exact(value) -> mpmath.mpf:
    """An entry of a table (int, Fraction, ``"p/q"`` string or :class:`Surd`) as a 50-digit number."""
    with mpmath.workdps(DIGITS):
        if isinstance(value, Surd):
            return value.mpf()
        f = Fraction(value)
        return mpmath.mpf(f.numerator) / f.denominator


def _vector(values, n: int, where: str) -> tuple:
    vals = tuple(values)
    if len(vals) != n:
        raise ValueError(f"{where}: needs {n} entries, got {len(vals)}")
    return vals


@dataclass(frozen=True)
class NystromTable:
    """An embedded RKN pair ``p(q)``.

    Attributes
    ----------
    name : str
        Used in error messages.
    c : tuple, length s
        Nodes (the first is 0).
    a : tuple of tuples
        Row ``i`` (0-based) holds ``a_i0 … a_i,i-1``; row 0 is empty.
    b, bp : tuple, length s
        Position and velocity weights of the solution carried on (order ``order``).
    b_hat, bp_hat : tuple, length s
        Weights of the embedded solution (order ``embedded_order``) used for the error estimate.
    order, embedded_order : int
    fsal : bool
        The last stage is evaluated at the new state (``c_s = 1``, last row = ``b``), so an
        accepted step's last force is the next step's first.
    source : str
        Where the numbers come from.
    """

    name: str
    c: tuple
    a: tuple
    b: tuple
    bp: tuple
    b_hat: tuple
    bp_hat: tuple
    order: int
    embedded_order: int
    fsal: bool = False
    source: str = field(default="", compare=False)

    def __post_init__(self):
        where = f"RKN table {self.name!r}"
        s = len(self.c)
        if s < 2:
            raise ValueError(f"{where}: needs at least 2 stages")
        rows = tuple(tuple(r) for r in self.a)
        if len(rows) != s or any(len(r) != i for i, r in enumerate(rows)):
            raise ValueError(f"{where}: a must have rows of lengths 0, 1, …, {s - 1} (explicit), got "
                             f"{[len(r) for r in rows]}")
        object.__setattr__(self, "a", rows)
        for key in ("b", "bp", "b_hat", "bp_hat"):
            object.__setattr__(self, key, _vector(getattr(self, key), s, f"{where}: {key}"))
        if not (1 <= self.embedded_order < self.order):
            raise ValueError(f"{where}: needs 1 <= embedded_order < order, got {self.embedded_order}, {self.order}")
        self._check(where)

    # -- exact values --------------------------------------------------------------------------
    @cached_property
    def _mp(self) -> dict:
        with mpmath.workdps(DIGITS):
            s = self.stages
            A = mpmath.matrix(s, s)
            for i, row in enumerate(self.a):
                for j, v in enumerate(row):
                    A[i, j] = exact(v)
            return {"c": [exact(v) for v in self.c], "A": A,
                    **{k: [exact(v) for v in getattr(self, k)] for k in ("b", "bp", "b_hat", "bp_hat")}}

    @property
    def stages(self) -> int:
        return len(self.c)

    @property
    def evals_per_step(self) -> int:
        """Force evaluations per accepted step (one fewer with first-same-as-last)."""
        return self.stages - 1 if self.fsal else self.stages

    def residuals(self, weights: str, order: int) -> dict[str, float]:
        """Residual of each checked condition for ``weights`` ``"main"`` or ``"embedded"`` at ``order``.

        Keys name the condition (``"bp c^3"``, ``"b c^1 (A c^2)"``, …); values are absolute residuals.
        """
        m = self._mp
        b, bp = (m["b"], m["bp"]) if weights == "main" else (m["b_hat"], m["bp_hat"])
        c, A, s = m["c"], m["A"], self.stages
        out: dict[str, float] = {}
        with mpmath.workdps(DIGITS):
            out["sum b"] = float(abs(mpmath.fsum(b) - mpmath.mpf(1) / 2))
            out["sum bp"] = float(abs(mpmath.fsum(bp) - 1))
            for k in range(order):
                out[f"bp c^{k}"] = float(abs(mpmath.fsum(bp[i] * c[i] ** k for i in range(s))
                                             - mpmath.mpf(1) / (k + 1)))
            for k in range(order - 1):
                out[f"b c^{k}"] = float(abs(mpmath.fsum(b[i] * c[i] ** k for i in range(s))
                                            - mpmath.mpf(1) / ((k + 1) * (k + 2))))
            for mm in range(order):
                Acm = [mpmath.fsum(A[i, j] * c[j] ** mm for j in range(i)) for i in range(s)]
                for k in range(order):
                    if k + mm + 3 <= order:
                        want = mpmath.mpf(1) / ((mm + 1) * (mm + 2) * (k + mm + 3))
                        out[f"bp c^{k} (A c^{mm})"] = float(abs(
                            mpmath.fsum(bp[i] * c[i] ** k * Acm[i] for i in range(s)) - want))
                    if k + mm + 4 <= order:
                        want = mpmath.mpf(1) / ((mm + 1) * (mm + 2) * (k + mm + 3) * (k + mm + 4))
                        out[f"b c^{k} (A c^{mm})"] = float(abs(
                            mpmath.fsum(b[i] * c[i] ** k * Acm[i] for i in range(s)) - want))
        return out

    def _check(self, where: str) -> None:
        m = self._mp
        c, A = m["c"], m["A"]
        with mpmath.workdps(DIGITS):
            if c[0] != 0:
                raise ValueError(f"{where}: the first node must be 0, got {float(c[0])!r}")
            for i in range(self.stages):
                r = mpmath.fsum(A[i, j] for j in range(i)) - c[i] ** 2 / 2
                if abs(r) > TOL:
                    raise ValueError(f"{where}: row {i + 1} sums to c²/2 + {float(r):.3g} (must be c_i²/2)")
        for weights, order in (("main", self.order), ("embedded", self.embedded_order)):
            for cond, r in self.residuals(weights, order).items():
                if r > TOL:
                    raise ValueError(f"{where}: {weights} weights (order {order}) fail {cond}: residual {r:.3g}")
        with mpmath.workdps(DIGITS):  # not of higher order by accident
            p = self.order
            r = abs(mpmath.fsum(m["bp"][i] * c[i] ** p for i in range(self.stages)) - mpmath.mpf(1) / (p + 1))
            if r <= TOL:
                raise ValueError(f"{where}: declared order {p} but the order-{p + 1} quadrature condition holds")
        if self.fsal:
            last = self.a[-1]
            if c[-1] != 1 or any(abs(exact(u) - exact(w)) > TOL for u, w in zip(last, self.b)) or \
                    abs(exact(self.b[-1])) > TOL:
                raise ValueError(f"{where}: declared first-same-as-last but the last stage is not the new state")

    # -- floats for the integrator -----------------------------------------------------------------
    @cached_property
    def arrays(self) -> dict[str, np.ndarray]:
        """``c`` (s,), ``A`` (s, s) strictly lower, ``b``, ``bp``, ``e`` = b − b̂, ``ep`` = b' − b̂' (s,), float64.

        The error weights are differences of the exact values, rounded once.
        """
        m = self._mp
        s = self.stages
        A = np.zeros((s, s))
        for i in range(s):
            for j in range(i):
                A[i, j] = float(m["A"][i, j])
        with mpmath.workdps(DIGITS):
            e = [float(u - w) for u, w in zip(m["b"], m["b_hat"])]
            ep = [float(u - w) for u, w in zip(m["bp"], m["bp_hat"])]
        out = {"c": np.array([float(v) for v in m["c"]]), "A": A, "b": np.array([float(v) for v in m["b"]]),
               "bp": np.array([float(v) for v in m["bp"]]), "e": np.array(e), "ep": np.array(ep)}
        for v in out.values():
            v.setflags(write=False)
        return out


def q(text: str) -> Fraction:
    """A rational entry written ``"p/q"`` (or an integer) — exact, never a float."""
    return Fraction(text)


__all__ = ["NystromTable", "Surd", "exact", "q", "TOL"]
