"""Double-double arithmetic on NumPy arrays: residuals of ``K x − λ M x`` from the elements.

A double-double number is an unevaluated sum ``hi + lo`` of two float64 with ``|lo| ≤ ulp(hi)/2``:
about 32 significant digits, at the cost of a few float64 operations each (Dekker's and Knuth's
error-free transformations, vectorised). The sensitivity routes keep mode shapes and their
derivatives in this form and compute every residual from the elements (masses, spring constants),
so the spring stretches ``x_a − x_b`` that cancel between nearly equal displacements of stiffly
joined masses are exact, and ``K`` is never formed.

Every function takes and returns pairs ``(hi, lo)`` of arrays (or of floats) of one shape.
"""

from __future__ import annotations

import numpy as np

#: Dekker's splitter 2^27 + 1 (splits a float64 into two 26-bit halves).
_SPLIT = 134217729.0


def two_sum(a, b):
    """``(s, e)`` with ``s = fl(a + b)`` and ``s + e = a + b`` exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _quick_two_sum(a, b):
    """``two_sum`` for ``|a| ≥ |b|``."""
    s = a + b
    return s, b - (s - a)


def _split(a):
    c = _SPLIT * a
    hi = c - (c - a)
    return hi, a - hi


def two_prod(a, b):
    """``(p, e)`` with ``p = fl(a b)`` and ``p + e = a b`` exactly (Dekker)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def dd(x, lo=None):
    """A double-double from float64 values (and optional low parts)."""
    x = np.asarray(x, dtype=float)
    return x, (np.zeros_like(x) if lo is None else np.asarray(lo, dtype=float))


def add(x, y):
    """``x + y`` (the accurate double-double sum: exact to about 2^-104 relative, even when x ≈ −y)."""
    s1, s2 = two_sum(x[0], y[0])
    t1, t2 = two_sum(x[1], y[1])
    s2 = s2 + t1
    s1, s2 = _quick_two_sum(s1, s2)
    s2 = s2 + t2
    return _quick_two_sum(s1, s2)


def neg(x):
    return -x[0], -x[1]


def sub(x, y):
    return add(x, neg(y))


def mul(x, y):
    """``x · y``."""
    p, e = two_prod(x[0], y[0])
    e = e + (x[0] * y[1] + x[1] * y[0])
    return _quick_two_sum(p, e)


def mul_f(x, f):
    """``x · f`` for float64 ``f``."""
    p, e = two_prod(x[0], f)
    e = e + x[1] * f
    return _quick_two_sum(p, e)


def div(x, y):
    """``x / y`` (one Newton correction of the float64 quotient)."""
    q1 = x[0] / y[0]
    r = sub(x, mul_f(y, q1))
    q2 = r[0] / y[0]
    r = sub(r, mul_f(y, q2))
    q3 = r[0] / y[0]
    s, e = _quick_two_sum(q1, q2)
    return add((s, e), (q3, 0.0 * q3))


def sqrt(x):
    """``√x`` for ``x ≥ 0`` (one Newton step on the float64 root)."""
    r = np.sqrt(x[0])
    safe = np.where(r > 0, r, 1.0)
    d = sub(x, two_prod(r, r))
    return _quick_two_sum(r, np.where(r > 0, d[0] / (2.0 * safe), 0.0))


def total(x):
    """The double-double sum over the first axis (pairwise: each level one vectorised :func:`add`).

    A 1-D input gives a pair of floats; an (N, ...) input a pair of arrays of shape (...).
    """
    hi, lo = np.asarray(x[0], dtype=float), np.asarray(x[1], dtype=float)
    if hi.shape[0] == 0:
        z = np.zeros(hi.shape[1:])
        return (0.0, 0.0) if hi.ndim == 1 else (z, z.copy())
    while hi.shape[0] > 1:
        if hi.shape[0] % 2:
            pad = np.zeros((1,) + hi.shape[1:])
            hi, lo = np.concatenate([hi, pad]), np.concatenate([lo, pad])
        hi, lo = add((hi[0::2], lo[0::2]), (hi[1::2], lo[1::2]))
    if hi.ndim == 1:
        return float(hi[0]), float(lo[0])
    return hi[0], lo[0]


def dot_weighted(x, w, y):
    """``Σ_i w_i x_i y_i`` over the first axis, double-double (x, y double-double, w float64; any of
    them may carry trailing axes that broadcast)."""
    return total(mul(mul_f(x, w), y))


def to_float(x) -> np.ndarray:
    """Rounded to float64."""
    return np.asarray(x[0] + x[1], dtype=float)


def scalar(x) -> tuple[float, float]:
    """A double-double of two floats (for broadcasting against arrays)."""
    return float(x[0]), float(x[1])


class Stencil:
    """``K x`` and ``M x`` of a spring network from its elements, in double-double.

    ``K = Bᵀ diag(k) B`` with ``B`` the spring incidence (+1 at end a, −1 at end b, walls
    omitted): ``(K x)_i = Σ_{s: a_s = i} k_s (x_a − x_b) − Σ_{s: b_s = i} k_s (x_a − x_b)``. The
    stretches are double-double differences (exact for float inputs) and each mass sums its
    springs' forces in a fixed order, one vectorised double-double addition per incident spring.

    Parameters
    ----------
    masses : ndarray, shape (N,)
    ends : ndarray of int, shape (S, 2)
        Spring ends, -1 for a wall (a spring from a mass to itself stores nothing).
    """

    def __init__(self, masses: np.ndarray, ends: np.ndarray):
        self.masses = np.asarray(masses, dtype=float)
        n = self.n = int(self.masses.shape[0])
        ends = np.asarray(ends, dtype=np.intp).reshape(-1, 2)
        a, b = ends[:, 0].copy(), ends[:, 1].copy()
        loop = a == b
        a[(a < 0) | loop], b[(b < 0) | loop] = n, n  # the pad index n holds a zero displacement
        self.a, self.b = a, b
        s = a.shape[0]
        # per mass: the springs it is an end of, with the sign of B (padded with spring s: a zero force)
        node = np.concatenate([a, b])
        spring = np.concatenate([np.arange(s), np.arange(s)])
        sign = np.concatenate([np.ones(s), -np.ones(s)])
        keep = node < n
        node, spring, sign = node[keep], spring[keep], sign[keep]
        order = np.argsort(node, kind="stable")
        node, spring, sign = node[order], spring[order], sign[order]
        counts = np.bincount(node, minlength=n)
        width = int(counts.max(initial=0))
        self.slots = np.full((n, width), s, dtype=np.intp)
        self.signs = np.zeros((n, width))
        if node.size:
            start = np.concatenate([[0], np.cumsum(counts)[:-1]])
            col = np.arange(node.size) - start[node]
            self.slots[node, col] = spring
            self.signs[node, col] = sign

    def stretches(self, x):
        """``B x``: ``x_a − x_b`` of every spring (walls 0), double-double, shape (S, ...)."""
        hi = np.concatenate([x[0], np.zeros((1,) + x[0].shape[1:])])
        lo = np.concatenate([x[1], np.zeros((1,) + x[1].shape[1:])])
        return sub((hi[self.a], lo[self.a]), (hi[self.b], lo[self.b]))

    def spread(self, f):
        """``Bᵀ f`` for spring values f (double-double, shape (S, ...)), shape (N, ...)."""
        hi = np.concatenate([f[0], np.zeros((1,) + f[0].shape[1:])])
        lo = np.concatenate([f[1], np.zeros((1,) + f[1].shape[1:])])
        shape = (self.n,) + f[0].shape[1:]
        acc = (np.zeros(shape), np.zeros(shape))
        extra = (slice(None),) + (None,) * (len(shape) - 1)
        for c in range(self.slots.shape[1]):
            idx, sg = self.slots[:, c], self.signs[:, c][extra]
            acc = add(acc, (hi[idx] * sg, lo[idx] * sg))
        return acc

    def stiffness(self, k: np.ndarray, x):
        """``K x`` with spring constants ``k`` (float64, shape (S,)), double-double, shape (N, ...)."""
        k = np.asarray(k, dtype=float)
        st = self.stretches(x)
        kk = k.reshape((-1,) + (1,) * (st[0].ndim - 1))
        return self.spread(mul_f(st, kk))

    def residual(self, k: np.ndarray, lam, x, masses: np.ndarray | None = None):
        """``K x − λ M x`` (``masses`` default: the stencil's), double-double, shape (N, ...)."""
        m = self.masses if masses is None else np.asarray(masses, dtype=float)
        m = m.reshape((-1,) + (1,) * (np.ndim(x[0]) - 1))
        return sub(self.stiffness(k, x), mul(mul_f(x, m), lam))


__all__ = ["two_sum", "two_prod", "dd", "add", "sub", "neg", "mul", "mul_f", "div", "sqrt", "total",
           "dot_weighted", "to_float", "scalar", "Stencil"]
