"""Extended-precision references for the sensitivity tests, built from the scene's TOML text.

Independent of springchain: the TOML is read with ``tomllib``, every mass and spring expression is
turned into an mpmath function of the parameters by SymPy (``sympify`` is fine here: the text is the
test's own), ``D = M^-1/2 K M^-1/2`` is diagonalised by ``mpmath.eigsy`` at ``dps`` digits (100 by
default: a central difference with step ``h = 1e-30·p`` then has truncation ~h² ≈ 1e-60 and rounding
~1e-100/h = 1e-70, settled far below float64 even when ω² spans 24 decades), and derivatives are
central (simple modes) or one-sided (repeated ω²) differences of the sorted spectrum.
"""

from __future__ import annotations

import tomllib
from fractions import Fraction

import mpmath
import sympy


def mp_exact(v) -> mpmath.mpf:
    """A float as the exact binary fraction it is, at the current precision."""
    f = Fraction(float(v))
    return mpmath.mpf(f.numerator) / f.denominator


class Reference:
    """A scene from its TOML text: element values as functions of the parameters, in mpmath.

    ``[masses]`` scenes and ``[chain]`` scenes (free/wall ends, expressions of ``i``).
    """

    def __init__(self, text: str):
        self.data = tomllib.loads(text)
        self.params = {k: float(v) for k, v in self.data["parameters"].items()}
        self.syms = {k: sympy.Symbol(k) for k in self.params}
        names = sorted(self.params)
        self.names = names
        i = sympy.Symbol("i")

        def fn(text, index=None):
            e = sympy.sympify(str(text), locals={**self.syms, "i": i})
            if index is not None:
                e = e.subs(i, index)
            return sympy.lambdify([self.syms[k] for k in names], e, "mpmath")

        if "chain" in self.data:
            ch = self.data["chain"]
            n = int(ch["n"])
            self.masses = [fn(ch["mass"], j) for j in range(n)]
            springs = [(j, j + 1, fn(ch["k"], j)) for j in range(n - 1)]
            if ch.get("left") == "wall":
                springs.insert(0, (-1, 0, fn(ch["k"], -1)))
            if ch.get("right") == "wall":
                springs.append((n - 1, -1, fn(ch["k"], n - 1)))
            self.springs = springs
        else:
            index = {name: j for j, name in enumerate(self.data["masses"])}
            index["wall"] = -1
            self.masses = [fn(e) for e in self.data["masses"].values()]
            self.springs = [(index[s["between"][0]], index[s["between"][1]], fn(s["k"])) for s in self.data["springs"]]
        self.n = len(self.masses)

    def values(self, changes: dict | None = None) -> list:
        """The parameters as mpmath numbers (exact binary fractions), ``changes`` added to them."""
        out = []
        for k in self.names:
            v = mp_exact(self.params[k])
            if changes and k in changes:
                v = v + changes[k]
            out.append(v)
        return out

    def modes(self, changes: dict | None = None):
        """``(ω² ascending, M-normalised shapes as lists, masses)`` at the current precision."""
        vals = self.values(changes)
        m = [f(*vals) for f in self.masses]
        r = [1 / mpmath.sqrt(x) for x in m]
        n = self.n
        D = mpmath.zeros(n, n)
        for a, b, f in self.springs:
            k = f(*vals)
            for p, sp_ in ((a, 1), (b, -1)):
                for q, sq in ((a, 1), (b, -1)):
                    if p >= 0 and q >= 0 and a != b:
                        D[p, q] += sp_ * sq * k * r[p] * r[q]
        w, E = mpmath.eigsy(D)
        order = sorted(range(n), key=lambda j: w[j])
        shapes = []
        for j in order:
            u = [E[i, j] for i in range(n)]
            big = max(range(n), key=lambda i: abs(u[i]))
            s = 1 if u[big] > 0 else -1
            shapes.append([s * u[i] * r[i] for i in range(n)])
        return [w[j] for j in order], shapes, m

    def central(self, p: str, dps: int = 100, rel_step: float = 1e-30):
        """Central differences: ``(ω², dω²/dp, shapes, dφ/dp, masses)`` (lists of floats) of every mode.

        Shapes at p ± h are given the sign of the shape at p (their M inner product positive).
        """
        with mpmath.workdps(dps):
            h = mp_exact(self.params[p]) * mpmath.mpf(rel_step)
            w0, s0, m = self.modes()
            wp, sp_, _ = self.modes({p: h})
            wm, sm, _ = self.modes({p: -h})
            dw = [(a - b) / (2 * h) for a, b in zip(wp, wm)]
            ds = []
            for j in range(self.n):
                a = _aligned(sp_[j], s0[j], m)
                b = _aligned(sm[j], s0[j], m)
                ds.append([float((x - y) / (2 * h)) for x, y in zip(a, b)])
            return ([float(x) for x in w0], [float(x) for x in dw], [[float(c) for c in s] for s in s0], ds,
                    [float(x) for x in m])

    def one_sided(self, p: str, dps: int = 100, rel_step: float = 1e-40):
        """Directional derivatives for increasing p: ``(ω², dω²/dp⁺, shapes at p⁺, dφ/dp⁺, masses)``.

        Eigenvalues: ``(λ(p + h) − λ(p))/h`` (error O(h)); shapes: the branch through ``p + h``,
        ``p + 2h``, ``p + 3h`` (second-order one-sided: ``(−5f₁ + 8f₂ − 3f₃)/(2h)`` with its limit
        ``3f₁ − 3f₂ + f₃`` at p), signs aligned along the branch.
        """
        with mpmath.workdps(dps):
            h = mp_exact(self.params[p]) * mpmath.mpf(rel_step)
            w0, _, m = self.modes()
            w1, s1, _ = self.modes({p: h})
            _, s2, _ = self.modes({p: 2 * h})
            _, s3, _ = self.modes({p: 3 * h})
            dw = [(a - b) / h for a, b in zip(w1, w0)]
            limits, ds = [], []
            for j in range(self.n):
                f1 = s1[j]
                f2 = _aligned(s2[j], f1, m)
                f3 = _aligned(s3[j], f1, m)
                limits.append([float(3 * a - 3 * b + c) for a, b, c in zip(f1, f2, f3)])
                ds.append([float((-5 * a + 8 * b - 3 * c) / (2 * h)) for a, b, c in zip(f1, f2, f3)])
            return [float(x) for x in w0], [float(x) for x in dw], limits, ds, [float(x) for x in m]


def _aligned(shape, ref, masses):
    dot = sum(a * b * m for a, b, m in zip(shape, ref, masses))
    return shape if dot >= 0 else [-c for c in shape]


__all__ = ["Reference", "mp_exact"]
