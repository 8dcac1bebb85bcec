"""An independent extended-precision reference for static equilibria of scenes with spring potentials.

Built from the scene's TOML data only (never the package's parser or solver): potentials parsed by
SymPy's ``parse_expr`` (trusted test text), parameter values taken as the exact binary fractions of
the floats the TOML holds, the total potential ``U(x) = Σ V_s(x_b − x_a) − Σ F_i x_i`` (gravity
``m_i g`` and constant forces), its gradient and Hessian by SymPy, evaluated by mpmath at ``dps``
digits.

The equilibrium is the one the package documents: the loads and pre-stress applied gradually from
rest, ``∇U(x) = (1 − λ) ∇U(0)`` followed from λ = 0 (x = 0) to λ = 1 by mpmath Newton at every load
step (steps halved until Newton contracts and lands within half a predictor step of the tangent's
prediction), the Hessian positive definite (Cholesky in mpmath) along the way. Outcomes:

* ``Reference.x`` (the equilibrium), ``.stiffness`` (V''(d_s) per spring) and ``.omega2`` (the
  eigenvalues of ``M^-1/2 H M^-1/2`` by ``mpmath.eigsy``): a stable equilibrium;
* ``.reached < 1``: the path ends (K singular or x running off) before the full loads;
* ``.margin``: how far the answer is from the edge of its case (a fold near λ = 1, or a spring's
  V'' near 0), so that a test can skip what float64 cannot decide.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from fractions import Fraction

import mpmath
import sympy as sp
from sympy.parsing.sympy_parser import parse_expr

DPS = 50
#: Displacements beyond which the path is taken to run off to infinity.
HUGE = mpmath.mpf(10) ** 120
#: Smallest load step, relative to the loads reached (or to FIRST of them for the first step), before the
#: path is declared ended.
MIN_STEP = mpmath.mpf(2) ** -50
FIRST = mpmath.mpf(2) ** -110


def exact(value) -> sp.Rational:
    """The exact binary value of a TOML float (or int)."""
    return sp.Rational(Fraction(float(value)))


@dataclass
class Scene:
    """U's pieces from TOML: n masses, springs (a, b, V(d)) with −1 a wall, masses, constant loads."""

    n: int
    springs: list
    masses: list
    loads: list
    d: sp.Symbol = field(default_factory=lambda: sp.Symbol("d", real=True))

    @classmethod
    def from_toml(cls, text: str) -> "Scene":
        data = tomllib.loads(text)
        params = {k: exact(v) for k, v in data.get("parameters", {}).items()}
        local = {k: sp.Symbol(k) for k in params}
        d = sp.Symbol("d", real=True)

        def value(expr: str) -> sp.Expr:
            return parse_expr(str(expr), local_dict=dict(local)).subs({local[k]: v for k, v in params.items()})

        names = list(data["masses"])
        masses = [value(data["masses"][k]) for k in names]
        index = {k: i for i, k in enumerate(names)}
        springs = []
        for s in data.get("springs", []):
            a, b = (-1 if e == "wall" else index[e] for e in s["between"])
            if "potential" in s:
                V = parse_expr(s["potential"], local_dict={**local, "d": d}).subs(
                    {local[k]: v for k, v in params.items()})
            else:
                V = value(s["k"]) * d**2 / 2
            springs.append((a, b, V))
        loads = [sp.Integer(0)] * len(names)
        if "gravity" in data:
            g = value(data["gravity"]["g"])
            loads = [m * g for m in masses]
        for f in data.get("forces", []):
            loads[index[f["on"]]] += value(f["f"])
        return cls(len(names), springs, masses, loads, d)


@dataclass
class Reference:
    """The reference answer (see the module docstring)."""

    reached: mpmath.mpf
    x: list | None = None
    extensions: list | None = None
    stiffness: list | None = None
    omega2: list | None = None
    #: How clearly the case is decided: for an equilibrium, min over the springs of |V''(d_s)| over that
    #: spring's stiffness scale (0 when the path ends within BEYOND past the full loads); for an ended
    #: path, the fraction of the loads it misses (0 within BEYOND).
    margin: float = 0.0

    @property
    def stable(self) -> bool:
        return self.x is not None and all(k > 0 for k in self.stiffness)


class _Funcs:
    def __init__(self, sc: Scene):
        self.sc = sc
        d = sc.d
        self.V = [sp.lambdify(d, V, "mpmath") for _, _, V in sc.springs]
        self.F = [sp.lambdify(d, sp.diff(V, d), "mpmath") for _, _, V in sc.springs]
        self.S = [sp.lambdify(d, sp.diff(V, d, 2), "mpmath") for _, _, V in sc.springs]
        self.load = [mpmath.mpf(sp.Rational(v).p) / sp.Rational(v).q for v in sc.loads]

    def ext(self, x):
        return [(x[b] if b >= 0 else 0) - (x[a] if a >= 0 else 0) for a, b, _ in self.sc.springs]

    def grad(self, x):
        g = [-f for f in self.load]
        for (a, b, _), F, dv in zip(self.sc.springs, self.F, self.ext(x)):
            t = F(dv)
            if a >= 0:
                g[a] -= t
            if b >= 0:
                g[b] += t
        return mpmath.matrix(g)

    def hess(self, x):
        H = mpmath.matrix(self.sc.n, self.sc.n)
        for (a, b, _), S, dv in zip(self.sc.springs, self.S, self.ext(x)):
            k = S(dv)
            for i, si in ((a, -1), (b, 1)):
                for j, sj in ((a, -1), (b, 1)):
                    if i >= 0 and j >= 0:
                        H[i, j] += si * sj * k
        return H

    def finite(self, x) -> bool:
        """V and V'' finite at x, and x within HUGE (beyond, a path is taken to run off: mpmath's exp of
        such arguments would exhaust GMP)."""
        if _norm(x) > HUGE:
            return False
        for V, S, dv in zip(self.V, self.S, self.ext(x)):
            for f in (V, S):
                try:
                    v = f(dv)
                except (ZeroDivisionError, ValueError, OverflowError):
                    return False
                if isinstance(v, mpmath.mpc) or not mpmath.isfinite(v):
                    return False
        return True


def _sign_margin(f: _Funcs, j: int, dv, k):
    """How clearly V''(d) = k has its sign: |k| over the spring's stiffness scale max(|V''(0)|, |k|, |V'(d)/d|)."""
    scale = max(abs(f.S[j](mpmath.mpf(0))), abs(k), abs(f.F[j](dv) / dv) if dv != 0 else mpmath.mpf(0))
    return abs(k) / scale if scale > 0 else mpmath.mpf(0)


def _pd(H) -> bool:
    try:
        mpmath.cholesky(H)
        return True
    except (ValueError, ZeroDivisionError):
        return False


def _norm(v):
    return max([abs(c) for c in v] + [mpmath.mpf(0)])


def _newton(f: _Funcs, x, shift, span):
    """Newton on grad(x) = shift from x; the root, or None unless it contracts and stays finite (a step that
    no longer contracts is the working precision's floor once it is below 10^(-DPS/2) of x)."""
    last = None
    for _ in range(60):
        if not f.finite(x):
            return None
        try:
            dx = mpmath.lu_solve(f.hess(x), f.grad(x) - shift)
        except (ZeroDivisionError, ValueError):
            return None
        size = _norm(dx)
        scale = max(_norm(x), span, mpmath.mpf(10) ** -300)
        if last is not None and size > last / 2:
            return x if last <= mpmath.mpf(10) ** (-DPS // 2) * scale else None
        x = x - dx
        last = size
        if size <= mpmath.mpf(10) ** (-DPS + 6) * scale:
            return x if f.finite(x) else None
    return None


def _softest(H):
    """The smallest eigenvalue of H, or None where H is not positive definite."""
    if not _pd(H):
        return None
    ev = mpmath.eigsy(H, eigvals_only=True)
    return min(ev[i] for i in range(H.rows))


def _along(f: _Funcs, x, pred, nxt) -> bool:
    """Newton's point within half the predicted change of every spring's extension (or of 1e-3 of the largest
    predicted change): a light mass's snap is not lost beside a heavy chain's large motion."""
    d0, dp, dn = f.ext(x), f.ext(pred), f.ext(nxt)
    step = [abs(a - b) for a, b in zip(dp, d0)]
    top = max(step + [mpmath.mpf(0)])
    floor = mpmath.mpf(10) ** (8 - mpmath.mp.dps) * max(_norm(nxt), mpmath.mpf(10) ** -300)
    return all(abs(c - b) <= max(s, top / 1000) / 2 + floor for b, c, s in zip(dp, dn, step))


def _follow(f: _Funcs, x, r0, lam, end):
    """Follow ∇U(x) = (1 − λ) r0 from (x, lam) to λ = end; returns (x, λ reached).

    A step is taken when Newton contracts from the tangent's prediction and lands within half the predicted
    change of every extension (:func:`_along`), the Hessian positive definite there with its smallest eigenvalue at least a quarter of the
    last one's and positive definite at three points between (a fold is approached, not stepped over onto
    another stable branch); else the step halves."""
    h = end - lam
    soft = _softest(f.hess(x))
    if soft is None:
        return x, lam
    while lam < end:
        tangent = -mpmath.lu_solve(f.hess(x), r0)
        target = min(end, lam + h)
        pred = x + (target - lam) * tangent
        span = _norm(pred - x)
        nxt = _newton(f, pred, (1 - target) * r0, span) if f.finite(pred) else None
        now = None if nxt is None or not _along(f, x, pred, nxt) else _softest(f.hess(nxt))
        if now is not None and not all(f.finite(x + c * (nxt - x)) and _pd(f.hess(x + c * (nxt - x)))
                                       for c in (mpmath.mpf(1) / 4, mpmath.mpf(1) / 2, mpmath.mpf(3) / 4)):
            now = None  # K indefinite between the two points: a snap over a barrier to another branch
        if now is None or now < soft / 4:
            h /= 2
            if h < MIN_STEP * max(lam, FIRST):
                return x, lam
            continue
        x, lam, soft = nxt, target, now
        h = min(end - lam, 2 * h) if lam < end else h
    return x, lam


#: The loads beyond the full ones the path must also reach for an equilibrium to count as clear of a fold.
BEYOND = mpmath.mpf(10) ** -6


def reference(text: str) -> Reference:
    """The reference equilibrium of the scene in ``text`` (walled pieces only: no free piece).

    ``margin``: 0 when the answer sits at the edge of its case (the path ends within :data:`BEYOND` of
    the full loads, on either side), else for a stable equilibrium min V''/max V'' over the springs, and
    for an ended path the fraction of the loads it misses."""
    sc = Scene.from_toml(text)
    with mpmath.workdps(DPS):
        f = _Funcs(sc)
        x = mpmath.matrix(sc.n, 1)
        r0 = f.grad(x)
        if not _pd(f.hess(x)):
            return Reference(mpmath.mpf(0), margin=0.0)  # no path starts (not generated by the tests)
        x, lam = _follow(f, x, r0, mpmath.mpf(0), mpmath.mpf(1))
        if lam < 1:
            return Reference(lam, margin=float(1 - lam) if 1 - lam > BEYOND else 0.0)
        _, beyond = _follow(f, x, r0, lam, 1 + BEYOND)
    # K's condition number sets the digits the answer needs: polish x and take the spectrum at enough of them
    with mpmath.workdps(DPS):
        stiff = [abs(S(dv)) for S, dv in zip(f.S, f.ext(x))]
        spread = max(stiff) / max(min([k for k in stiff if k > 0] or [mpmath.mpf(1)]), mpmath.mpf(10) ** -300)
    hi = min(DPS + 2 * int(mpmath.log10(max(spread, 1))) + 20, 400)
    with mpmath.workdps(hi):
        x = mpmath.matrix([mpmath.mpf(v) for v in x])
        for _ in range(40):  # Newton at the full loads, at hi digits
            dx = mpmath.lu_solve(f.hess(x), f.grad(x))
            x = x - dx
            if _norm(dx) <= mpmath.mpf(10) ** (-hi + 10) * max(_norm(x), mpmath.mpf(10) ** -300):
                break
        ext = f.ext(x)
        stiff = [S(dv) for S, dv in zip(f.S, ext)]
        m = [mpmath.mpf(sp.Rational(v).p) / sp.Rational(v).q for v in sc.masses]
        H = f.hess(x)
        D = mpmath.matrix(sc.n, sc.n)
        for i in range(sc.n):
            for j in range(sc.n):
                D[i, j] = H[i, j] / mpmath.sqrt(m[i] * m[j])
        ev = mpmath.eigsy(D, eigvals_only=True)
        margin = min(float(_sign_margin(f, j, dv, k)) for j, (dv, k) in enumerate(zip(ext, stiff)))
        margin = margin if beyond >= 1 + BEYOND else 0.0
        return Reference(mpmath.mpf(1), [x[i] for i in range(sc.n)], ext, stiff,
                         sorted(ev[i] for i in range(sc.n)), margin)


__all__ = ["Reference", "Scene", "reference", "exact", "DPS"]
