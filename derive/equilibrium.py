"""The static equilibrium of a scene with spring laws, and the checks that it is a stable one.

The total potential ``U(x) = Σ_s V_s(d_s(x)) − Σ_i F_i x_i`` (springs, and the constant loads:
gravity ``m_i g`` and forces that do not depend on t) has the gradient
``G_i = Σ_s V_s'(d_s) ∂d_s/∂x_i − F_i`` and the Hessian ``K = Σ_s V_s''(d_s) b_s b_sᵀ``, both
assembled spring by spring from the exact symbolic derivatives. The equilibrium solves G(x) = 0:

1. **Exactly at x = 0** when every G_i(0) simplifies to 0 (V'(0) = 0 and no constant loads, or
   tensions that balance): then x_eq = 0 and K = Σ V_s''(0) b bᵀ are closed forms.
2. **Otherwise by Newton** from x = 0 at the scene's parameter values: float64 Newton with a
   Levenberg–Marquardt safeguard on U, then iterative refinement in mpmath (the residual G at 40,
   80, … digits with the parameters as exact rationals, the correction from the float64 Hessian)
   until two precisions agree to 1e-18 relative: correct to float64 even where float64 alone could
   not settle it. Each free piece (no spring to a wall) keeps its centre of mass at the rest
   position (its rigid translation is otherwise undetermined).

Refused in one line (a :class:`SceneError` naming the spring's key): V, V' or V'' not finite at
the equilibrium (a singularity or a kink), V'' ≤ 0 there (not a stable spring; the stiffness and the
extension are named), a free piece under a net constant load (it accelerates: no equilibrium), or
no equilibrium found from the rest configuration.
"""

from __future__ import annotations

from dataclasses import dataclass
import mpmath
import numpy as np
import sympy as sp

from .accurate import exact_values
from .errors import SceneError
from .scene_loader import MAX_MAGNITUDE, MIN_MAGNITUDE
from .mp_eval import mp_function
from .potential import SpringLaw

#: Relative agreement of two successive precisions accepted as converged.
AGREE = 1e-18
#: Float64 Newton iterations before giving up.
MAX_NEWTON = 200
#: Largest working precision tried (digits).
MAX_DPS = 640


@dataclass(frozen=True)
class Equilibrium:
    """The static equilibrium x_eq and the springs' extensions and stiffnesses there.

    Attributes
    ----------
    x : tuple of sympy.Expr
        x_eq per coordinate: closed forms (``closed_form``) or correctly rounded numbers (Float).
    extensions : tuple of sympy.Expr
        d_s at x_eq per spring (same kind).
    stiffness : tuple of sympy.Expr
        V_s''(d_s) per spring: the entries of K about x_eq.
    closed_form : bool
        Whether the values are closed forms in the parameters (x_eq = 0).
    how : str
        How it was found, for the report.
    """

    x: tuple
    extensions: tuple
    stiffness: tuple
    closed_form: bool
    how: str

    @property
    def at_rest(self) -> bool:
        """Whether x_eq = 0 exactly (the springs' rest configuration)."""
        return self.closed_form and all(v == 0 for v in self.x)


def _ext(a: int, b: int, x):
    """d = x_b − x_a, a wall end (−1) counting 0."""
    return (x[b] if b >= 0 else 0) - (x[a] if a >= 0 else 0)


def _mpv(v, dps: int):
    """A SymPy number (exact where it is rational) or an mpf as an mpmath value at ``dps`` digits."""
    if isinstance(v, mpmath.mpf):
        return v
    if isinstance(v, (int, sp.Integer)):
        return mpmath.mpf(int(v))
    if isinstance(v, sp.Rational):
        return mpmath.mpf(v.p) / v.q
    return mpmath.mpf(sp.N(v, dps + 10)._mpf_)


def _finite(v) -> bool:
    try:
        return bool(mpmath.isfinite(v)) and not isinstance(v, mpmath.mpc)
    except TypeError:
        return False


def _refuse_value(file: str, law: SpringLaw, what: str, d_value, why: str, accepted: str) -> SceneError:
    return SceneError(file, law.where, f"{what} at the equilibrium extension d = {float(d_value):.6g}: "
                                       f"{why}; accepted: {accepted}")


def _at_rest_finite(file: str, law: SpringLaw, subs: dict) -> None:
    """V, V', V'' finite at d = 0, where Newton starts (e.g. not r0/d: write the potential in the
    extension from the rest length, r = r0 + d)."""
    if any(e.has(sp.DiracDelta, sp.Heaviside, sp.sign, sp.Abs) for e in (law.force, law.stiffness)):
        raise SceneError(file, law.where, f"{sp.sstr(law.energy)}: has a kink or a jump (V' or V'' holds Abs or "
                         "sign): not twice differentiable; accepted: a potential with two continuous derivatives, "
                         "e.g. d**2 instead of sqrt(d**2)")
    with mpmath.workdps(30):
        for name, expr in (("V", law.energy), ("V'", law.force), ("V''", law.stiffness)):
            f = mp_function(expr, (law.d, *subs))
            try:
                v = f(mpmath.mpf(0), *[_mpv(r, 30) for r in subs.values()])
            except (ZeroDivisionError, ValueError, OverflowError, TypeError, NameError):
                v = mpmath.nan
            if isinstance(v, mpmath.mpc) and v.imag == 0:
                v = v.real
            if not _finite(v):
                raise SceneError(file, law.where, f"{sp.sstr(law.energy)}: {name}(0) = {mpmath.nstr(v, 6)} is not "
                                 "finite at the rest configuration d = 0; accepted: a potential finite and twice "
                                 "differentiable at d = 0, written in the extension from the rest length "
                                 "(e.g. r = r0 + d for a pair at distance r)")


def check_law(file: str, law: SpringLaw, d_value, subs: dict, *, closed_form: sp.Expr | None = None) -> sp.Expr:
    """V, V', V'' finite at ``d_value`` and V'' > 0 there; returns V''(d_value) (closed form or Float).

    Parameters
    ----------
    d_value : sympy number or mpf
        The spring's extension at the equilibrium.
    subs : dict
        Parameter symbols (and ``i`` in a chain) to exact values.
    closed_form : sympy.Expr, optional
        V''(d_eq) as a closed form (x_eq = 0), returned after the checks.
    """
    dps = 40
    with mpmath.workdps(dps):
        dv = _mpv(d_value, dps)
        if any(e.has(sp.DiracDelta, sp.Heaviside, sp.sign) for e in (law.force, law.stiffness)):
            raise _refuse_value(file, law, "V'' has a kink or a jump (Abs, sign)", dv,
                                "not twice differentiable there",
                                "a potential with two continuous derivatives at the equilibrium, e.g. d**2 instead of abs(d)")
        vals = []
        for name, expr in (("V", law.energy), ("V'", law.force), ("V''", law.stiffness)):
            f = mp_function(expr, (law.d, *subs))
            try:
                v = f(dv, *[_mpv(r, dps) for r in subs.values()])
            except (ZeroDivisionError, ValueError, OverflowError, TypeError, NameError):
                v = mpmath.nan
            if isinstance(v, mpmath.mpc) and abs(v.imag) <= mpmath.mpf(10) ** (-dps + 5) * max(abs(v.real), 1):
                v = v.real
            if not _finite(v):
                raise _refuse_value(file, law, f"{name} is not finite", dv, f"{name}(d) = {mpmath.nstr(v, 6)}",
                                    "a potential finite and twice differentiable at the equilibrium "
                                    "(e.g. a Lennard-Jones pair written about its minimum, d > -r0)")
            vals.append(v)
        if not vals[2] > 0:
            raise _refuse_value(file, law, f"stiffness V''(d) = {mpmath.nstr(vals[2], 6)}", dv,
                                "not positive (this spring is not stable there)",
                                "a potential with V''(d) > 0 at the equilibrium")
        stiff = vals[2]
        if not MIN_MAGNITUDE <= stiff <= MAX_MAGNITUDE:  # the range a spring's k is held to
            raise _refuse_value(file, law, f"stiffness V''(d) = {mpmath.nstr(mpmath.mpf(stiff), 6)}", dv,
                                f"outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g}",
                                f"a potential whose stiffness at the equilibrium lies in {MIN_MAGNITUDE:g} to "
                                f"{MAX_MAGNITUDE:g}, as a spring's k")
    if closed_form is not None:
        return closed_form
    return sp.Float(mpmath.nstr(stiff, 25), 17)


class _Problem:
    """The gradient and Hessian of U at the scene's values, in float64 and in mpmath."""

    def __init__(self, n: int, springs, loads, subs: dict, pieces):
        self.n = n
        self.springs = springs  # (a, b, law)
        self.pieces = pieces
        syms = list(subs)
        self.values = [subs[s] for s in syms]
        self.f64 = [(a, b, sp.lambdify([law.d] + syms, law.energy, "numpy"),
                     sp.lambdify([law.d] + syms, law.force, "numpy"),
                     sp.lambdify([law.d] + syms, law.stiffness, "numpy")) for a, b, law in springs]
        self.fmp = [(a, b, mp_function(law.force, (law.d, *syms))) for a, b, law in springs]
        self.loads = list(loads)
        self.load_f = np.array([float(v) for v in self.loads])
        self.fvals = [float(v) for v in self.values]
        # rigid translations of free pieces: w = masses on the piece (centre of mass stays)
        self.w = np.zeros((len(pieces), n))
        for r, (piece, masses) in enumerate(pieces):
            for i, m in zip(piece, masses):
                self.w[r, i] = m

    def _d(self, a, b, x):
        return (x[b] if b >= 0 else 0.0) - (x[a] if a >= 0 else 0.0)

    def energy(self, x) -> float:
        e = -float(self.load_f @ x)
        with np.errstate(all="ignore"):
            for a, b, V, _, _ in self.f64:
                e += float(V(self._d(a, b, x), *self.fvals))
        return e

    def gradient(self, x) -> np.ndarray:
        g = -self.load_f.copy()
        with np.errstate(all="ignore"):
            for a, b, _, F, _ in self.f64:
                t = float(F(self._d(a, b, x), *self.fvals))
                if a >= 0:
                    g[a] -= t
                if b >= 0:
                    g[b] += t
        return g

    def hessian(self, x) -> np.ndarray:
        H = np.zeros((self.n, self.n))
        with np.errstate(all="ignore"):
            for a, b, _, _, S in self.f64:
                k = float(S(self._d(a, b, x), *self.fvals))
                for i, si in ((a, -1.0), (b, 1.0)):
                    for j, sj in ((a, -1.0), (b, 1.0)):
                        if i >= 0 and j >= 0:
                            H[i, j] += si * sj * k
        return H

    def augmented(self, H) -> np.ndarray:
        """H + Σ w wᵀ over free pieces: nonsingular, and its solution keeps each centre of mass."""
        return H + self.w.T @ self.w

    def gradient_mp(self, x, dps: int):
        with mpmath.workdps(dps):
            vals = [_mpv(r, dps) for r in self.values]
            g = [-_mpv(v, dps) for v in self.loads]
            for a, b, F in self.fmp:
                d = (x[b] if b >= 0 else 0) - (x[a] if a >= 0 else 0)
                t = F(d, *vals)
                if a >= 0:
                    g[a] -= t
                if b >= 0:
                    g[b] += t
            return g


def newton(problem: _Problem) -> tuple[list, str] | None:
    """x_eq in mpmath (correct to float64), or None if Newton does not converge."""
    n = problem.n
    x = np.zeros(n)
    mu = 0.0
    e = problem.energy(x)
    for it in range(MAX_NEWTON):
        g = problem.gradient(x)
        if not np.all(np.isfinite(g)):
            return None
        H = problem.augmented(problem.hessian(x))
        scale = max(np.max(np.abs(np.diag(H))), 1e-300)
        step = None
        for _ in range(60):
            try:
                cand = x - np.linalg.solve(H + mu * scale * np.eye(n), g)
            except np.linalg.LinAlgError:
                mu = max(mu * 10, 1e-8)
                continue
            ec = problem.energy(cand)
            if np.isfinite(ec) and ec <= e + 1e-12 * abs(e):
                step = cand
                break
            mu = max(mu * 10, 1e-8)
        if step is None:
            return None
        moved = np.max(np.abs(step - x))
        x, e = step, problem.energy(step)
        mu = mu / 10 if mu > 1e-12 else 0.0
        if moved <= 1e-15 * max(np.max(np.abs(x)), 1e-300) or moved == 0.0:
            break
    else:
        return None
    # iterative refinement in extended precision: residual in mpmath, correction by the float64 Hessian
    H = problem.augmented(problem.hessian(x))
    try:
        lu = np.linalg.inv(H)
    except np.linalg.LinAlgError:
        return None
    prev = None
    dps = 40
    xs = [mpmath.mpf(float(v)) for v in x]
    while dps <= MAX_DPS:
        with mpmath.workdps(dps):
            xs = [mpmath.mpf(v) for v in xs]
            for _ in range(200):
                g = problem.gradient_mp(xs, dps)
                corr = lu @ np.array([float(v) for v in g])
                xs = [xi - mpmath.mpf(float(c)) for xi, c in zip(xs, corr)]
                size = max([abs(v) for v in xs] + [mpmath.mpf(10) ** (-300)])
                if max(abs(float(c)) for c in corr) <= float(size) * 10.0 ** (-dps + 8):
                    break
            cur = [float(v) for v in xs]
            if prev is not None and all(abs(p - c) <= AGREE * max(max(abs(v) for v in cur), 1e-300)
                                        for p, c in zip(prev, cur)):
                return xs, f"Newton from x = 0 (float64), refined in mpmath to {dps} digits"
            prev = cur
        dps *= 2
    return None


def solve(file: str, n: int, springs, loads, params: dict, values: dict, pieces, *,
          load_keys: str = "the loads") -> Equilibrium:
    """The static equilibrium of ``n`` coordinates, refusing what is not a stable one.

    Parameters
    ----------
    file : str
        The scene file (for messages).
    n : int
        Number of coordinates.
    springs : list of (int, int, SpringLaw)
        Ends (−1 = wall) and law of every spring.
    loads : list of sympy.Expr
        Constant force on each coordinate (gravity m g, forces free of t).
    params : dict
        Parameter name -> symbol; ``values`` parameter name -> float.
    pieces : list of (list of int, list of sympy.Expr)
        Free pieces (mass indices) with their masses.
    """
    subs = exact_values(params, values)
    for _, _, law in springs:
        if law.given:
            _at_rest_finite(file, law, subs)
    grad = [-(load) for load in loads]
    for a, b, law in springs:
        t0 = law.force.subs(law.d, 0)
        if a >= 0:
            grad[a] -= t0
        if b >= 0:
            grad[b] += t0
    for piece, _ in pieces:  # a free piece under a net constant load accelerates: no equilibrium
        net = sp.Add(*(loads[i] for i in piece))
        if sp.simplify(net) != 0 and abs(float(net.subs(subs))) > 0:
            raise SceneError(file, load_keys, f"net constant force {sp.sstr(sp.simplify(net))} on the free piece of masses "
                             f"{', '.join(str(i) for i in piece)}: it accelerates, so there is no static equilibrium; "
                             "accepted: a spring from that piece to a wall, or no constant load on it")
    if all(sp.simplify(gi) == 0 for gi in grad):
        ext = tuple(sp.Integer(0) for _ in springs)
        stiff = tuple(check_law(file, law, sp.Integer(0), subs, closed_form=sp.factor(law.stiffness.subs(law.d, 0)))
                      for _, _, law in springs)
        return Equilibrium(tuple(sp.Integer(0) for _ in range(n)), ext, stiff, True,
                           "x = 0: every spring at rest balances (V'(0) = 0 or balanced tensions)")
    problem = _Problem(n, springs, [ld.subs(subs) for ld in loads], subs,
                       [(piece, [float(m.subs(subs)) for m in masses]) for piece, masses in pieces])
    found = newton(problem)
    if found is None:
        raise SceneError(file, springs[0][2].where if springs else None,
                         "no static equilibrium found: Newton from the rest configuration x = 0 (with a "
                         "Levenberg-Marquardt safeguard) did not converge; accepted: springs and loads "
                         "with a stable equilibrium (V''(d) > 0 there)")
    xs, how = found
    xv = tuple(sp.Float(mpmath.nstr(v, 25), 17) for v in xs)
    ext, stiff = [], []
    for a, b, law in springs:
        with mpmath.workdps(40):
            dv = (xs[b] if b >= 0 else 0) - (xs[a] if a >= 0 else 0)
        stiff.append(check_law(file, law, dv, subs))
        ext.append(sp.Float(mpmath.nstr(dv, 25), 17))
    return Equilibrium(xv, tuple(ext), tuple(stiff), False, how)


__all__ = ["Equilibrium", "solve", "check_law", "SpringLaw"]
