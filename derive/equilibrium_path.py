"""The loading path of :mod:`derive.equilibrium` in the positions x: continuation for springs that close loops.

``U(x) = Σ_s V_s(d_s) − Σ_i F_i x_i`` at the scene's values (:class:`PathProblem`: gradient and Hessian spring by
spring, in float64 and in mpmath). The out-of-balance force at rest G(0) is applied as λ G(0), λ: 0 → 1,
following ``Σ_s (V_s'(d_s) − V_s'(0)) b_s + λ G(0) = 0`` from x = 0 (:func:`path`): tangent predictor
``dx/dλ = −K⁻¹ G(0)``, Newton correctors that must contract (each step or else each residual at most
:data:`CONTRACTION` of the last), the load step halved otherwise and doubled after a success; K positive
definite at every accepted point. Float64 first; the residual and K in mpmath (:data:`CORRECT_DPS` digits
beyond log10 of the spread of the springs' stiffnesses) where K is ill-conditioned beyond
:data:`ILL_CONDITIONED` or float64 does not contract. A residual counts as converged at its floor: the forces at
play, the rounding of the extensions formed from x (:meth:`PathProblem.floor`), or the evaluation's own noise
(the residual 20 digits finer). Each extension stays inside its potential's domain (:func:`domain`). Then
:func:`refine` in mpmath to float64's last bit; :func:`descent` where x = 0 itself is not stable.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass

import mpmath

import numpy as np
import scipy.linalg
import sympy as sp

from .mp_eval import mp_function
from .potential import SpringLaw

#: Relative agreement of two successive precisions accepted as converged.
AGREE = 1e-18
#: Float64 Newton iterations of the descent (a scene whose rest configuration is not stable) before giving up.
MAX_NEWTON = 200
#: Largest working precision tried (digits).
MAX_DPS = 640
#: Load steps of the continuation (accepted or halved) before giving up, and the smallest load step:
#: MIN_STEP of the loads reached (the end of a path found to that relative accuracy), or FIRST_STEP of
#: the full loads for the first step (a spring so soft that its linear range holds less is still followed).
MAX_PATH = 4000
MIN_STEP = 1e-10
FIRST_STEP = 1e-60
#: Newton corrector: iterations, the contraction each step must show (a larger step diverges or jumps
#: branches), the step (relative to the size of x) that converges, and the residual (relative to the force
#: scale) below which a step that no longer contracts is float64's floor, accepted.
MAX_CORRECT = 20
CONTRACTION = 0.75
CORRECT_TOL = 1e-13
RESIDUAL_NOISE = 1e-10
#: A step below CORRECT_TOL converges only with the residual below this of the forces at play (or float64's
#: floor, :meth:`PathProblem.floor`, at FLOAT_DIGITS).
RESIDUAL_SETTLED = 1e-6
FLOAT_DIGITS = 16
#: The descent's stopping rule: a step below CORRECT_TOL of x, or one that no longer contracts below this.
DESCENT_NOISE = 1e-7
#: A step may lower K's smallest eigenvalue to this fraction of its value at most, and K must be positive definite
#: at three points between (else the load step is halved): a fold (K singular) is approached and found, not
#: stepped over onto another stable branch (a snap-through over an energy barrier).
FOLD_GUARD = 0.25
#: A corrector's point whose extensions differ from the predictor's by more than this many times their predicted
#: change (or BRANCH_SHARE of the largest predicted change) is refused (a jump to another branch, or a step too
#: long for the path's curvature: the load step is halved).
BRANCH = 0.5
BRANCH_SHARE = 1e-3
#: ... beyond the corrector's own noise, this fraction of the displacements at the spring's ends.
BRANCH_NOISE = 1e-12
#: Newton iterations per precision of the mpmath refinement.
MAX_REFINE = 60
#: Digits of the corrector's residual where float64's does not contract, beyond log10 of the spread of the
#: springs' stiffnesses (K's condition), and at most.
CORRECT_DPS = 30
MAX_CORRECT_DPS = 330
#: Condition number of K above which the continuation solves with K in mpmath (float64 would lose a
#: soft spring beside a stiff one, or the residual's noise would swamp the step).
ILL_CONDITIONED = 1e10


def mp_vector(v, dps: int):
    """A SymPy number (exact where it is rational) or an mpf as an mpmath value at ``dps`` digits."""
    if isinstance(v, mpmath.mpf):
        return v
    if isinstance(v, (int, sp.Integer)):
        return mpmath.mpf(int(v))
    if isinstance(v, sp.Rational):
        return mpmath.mpf(v.p) / v.q
    return mpmath.mpf(sp.N(v, dps + 10)._mpf_)

def domain(law: SpringLaw, subs: dict) -> tuple[float, float]:
    """The open interval ``(lo, hi)`` of extensions around d = 0 on which V is defined and continuous
    at the scene's values: a pole (Lennard-Jones at ``d = −r0``), a logarithm's or a root's zero
    bound it. ``(−inf, inf)`` for polynomials and entire functions, or where SymPy cannot tell (then
    the finiteness checks along the path guard it).

    Parameters
    ----------
    law : SpringLaw
    subs : dict
        Parameter symbols (and ``i``) to exact values.
    """
    energy = law.energy.subs(subs)
    if not law.given or not any(isinstance(p, sp.log) or (isinstance(p, sp.Pow) and not
                                                            (p.exp.is_Integer and p.exp >= 0))
                                for p in sp.preorder_traversal(energy)):
        return -np.inf, np.inf
    return _domain(energy, law.d)


@functools.lru_cache(maxsize=256)
def _domain(energy: sp.Expr, d: sp.Symbol) -> tuple[float, float]:
    from sympy.calculus.util import continuous_domain

    try:
        where = continuous_domain(energy, d, sp.S.Reals)
    except Exception:  # noqa: BLE001 - SymPy's set solver: anything it cannot decide leaves the line open
        return -np.inf, np.inf
    parts = where.args if isinstance(where, sp.Union) else (where,)
    for part in parts:
        if isinstance(part, sp.Interval) and part.inf < 0 < part.sup:
            return float(part.inf), float(part.sup)
    return -np.inf, np.inf


class PathProblem:
    """The gradient and Hessian of U at the scene's values, in float64 and in mpmath."""

    def __init__(self, n: int, springs, loads, subs: dict, pieces):
        self.n = n
        self.springs = springs  # (a, b, law)
        #: How many corrector solves needed the residual in mpmath (for the report), and whether one failed
        #: only because float64 could not hold its positions (an extension below float64's resolution of x).
        self.mp_corrections = 0
        self.float64_limited = False
        syms = list(subs)
        self.values = [subs[s] for s in syms]
        self.f64 = [(a, b, sp.lambdify([law.d] + syms, law.energy, "numpy"),
                     sp.lambdify([law.d] + syms, law.force, "numpy"),
                     sp.lambdify([law.d] + syms, law.stiffness, "numpy")) for a, b, law in springs]
        self.fmp = [(a, b, mp_function(law.force, (law.d, *syms))) for a, b, law in springs]
        self.smp = [(a, b, mp_function(law.stiffness, (law.d, *syms))) for a, b, law in springs]
        #: The third and fourth derivatives of V at d = 0 of every spring (the reach of the linearisation at
        #: rest, for the first load step).
        with mpmath.workdps(30):
            rest_vals = [mp_vector(v, 30) for v in self.values]
            self.rest_derivatives = [
                tuple(_float(mp_function(sp.diff(law.stiffness, law.d, k), (law.d, *syms)), rest_vals) for k in (1, 2))
                for _, _, law in springs]
        self.loads = list(loads)
        self.load_f = np.array([float(v) for v in self.loads])
        self.fvals = [float(v) for v in self.values]
        ends = np.array([(a, b) for a, b, _ in springs], dtype=np.intp).reshape(-1, 2)
        self.a, self.b = ends[:, 0], ends[:, 1]
        #: V'(0) of every spring (float64 and, per precision, mpmath): the path's residual is taken from them.
        self.rest = self.tensions(np.zeros(n))
        self._rest_mp: dict = {}
        bounds = np.array([domain(law, subs) for _, _, law in springs]).reshape(-1, 2)
        self.lo, self.hi = bounds[:, 0], bounds[:, 1]
        # rigid translations of free pieces: w = masses on the piece (centre of mass stays)
        self.w = np.zeros((len(pieces), n))
        for r, (piece, masses) in enumerate(pieces):
            for i, m in zip(piece, masses):
                self.w[r, i] = m

    def extensions(self, x) -> np.ndarray:
        """d = x_b − x_a of every spring (a wall end 0), shape (S,)."""
        xe = np.append(np.asarray(x, dtype=float), 0.0)  # index −1 = wall
        return xe[self.b] - xe[self.a]

    def inside(self, x) -> bool:
        """Every extension strictly inside its potential's domain, and x finite."""
        d = self.extensions(x)
        return bool(np.all(np.isfinite(d)) and np.all(d > self.lo) and np.all(d < self.hi))

    def energy(self, x) -> float:
        e = -float(self.load_f @ x)
        with np.errstate(all="ignore"):
            for (_, _, V, _, _), d in zip(self.f64, self.extensions(x)):
                e += float(V(d, *self.fvals))
        return e

    def tensions(self, x) -> np.ndarray:
        with np.errstate(all="ignore"):
            return np.array([float(F(d, *self.fvals)) for (_, _, _, F, _), d in zip(self.f64, self.extensions(x))])

    def digits(self, x) -> int:
        """Working digits for K's solves at x: :data:`CORRECT_DPS` beyond log10 of the spread of the springs'
        stiffnesses there (K's condition number, up to the factors of the topology)."""
        with np.errstate(all="ignore"):
            k = np.abs([float(S(d, *self.fvals)) for (_, _, _, _, S), d in zip(self.f64, self.extensions(x))])
        k = k[np.isfinite(k) & (k > 0)]
        spread = float(np.log10(np.max(k)) - np.log10(np.min(k))) if k.size else 0.0
        return int(min(MAX_CORRECT_DPS, CORRECT_DPS + max(0.0, spread)))

    def finite(self, x) -> bool:
        """The float64 tensions at x finite (no argument of an exponential beyond float range: mpmath is only
        asked where float64 could still be)."""
        return bool(np.all(np.isfinite(self.tensions(x))))

    def floor(self, x, applied, digits: float) -> np.ndarray:
        """The residual a ``digits``-digit evaluation at x cannot get below, per coordinate (N,): the forces
        at that mass (:meth:`local_scale`) to ``10^(4 − digits)``, or the rounding of the extensions formed
        from the positions, ``Σ |V''(d)|·(|x_a| + |x_b|)`` over its springs (an extension much smaller than x
        carries ε·|x|), to ``10^(3 − digits)``; never above RESIDUAL_SETTLED of the largest applied load (a
        point next to a pole, where V'' is huge, cannot justify itself by its own rounding: the corrector goes
        to more digits instead)."""
        xe = np.append(np.abs(np.asarray(x, dtype=float)), 0.0)
        with np.errstate(all="ignore"):
            k = np.abs([float(S(d, *self.fvals)) for (_, _, _, _, S), d in zip(self.f64, self.extensions(x))])
            spread = self._gather(np.nan_to_num(k * (xe[self.a] + xe[self.b]), nan=0.0, posinf=0.0))
        floor = np.maximum(10.0 ** (4 - digits) * self.local_scale(x, applied), 10.0 ** (3 - digits) * spread)
        cap = RESIDUAL_SETTLED * float(np.max(np.abs(np.asarray(applied, dtype=float)), initial=0.0))
        return np.minimum(floor, cap) if cap > 0 else floor

    def local_scale(self, x, applied) -> np.ndarray:
        """The forces at play at each mass (N,), for residuals at their floor: the applied part of the loads
        and pre-stress there, and the tensions (at x and at rest) of its springs. Per mass: a weak spring
        beside a heavy one is held to its own forces, not to the heavy one's."""
        with np.errstate(all="ignore"):
            t = np.nan_to_num(np.abs(self.tensions(x)) + np.abs(self.rest), nan=np.inf)
            out = np.abs(np.asarray(applied, dtype=float)) + self._gather(t)
        return np.where(out > 0, out, 1e-300)

    def _gather(self, per_spring) -> np.ndarray:
        """``Σ`` over the springs at each mass of a non-negative per-spring quantity, shape (N,)."""
        out = np.zeros(self.n)
        for a, b, v in zip(self.a, self.b, per_spring):
            if a >= 0:
                out[a] += v
            if b >= 0:
                out[b] += v
        return out

    def _spread(self, t, g) -> np.ndarray:
        """``Σ_s t_s b_s`` into g (N,): +t on the second end, −t on the first."""
        with np.errstate(all="ignore"):
            for a, b, ts in zip(self.a, self.b, t):
                if a >= 0:
                    g[a] -= ts
                if b >= 0:
                    g[b] += ts
        return g

    def residual(self, x, lam: float, r0: np.ndarray) -> np.ndarray:
        """``G(x) − (1 − λ) G(0) = Σ_s (V'(d_s) − V'(0)) b_s + λ G(0)``: the loading path's equation, with
        the springs' tensions beyond their rest ones (no rounding of G(0) against itself, so a load step
        of 1e-20 of the loads is resolved as well as the full loads)."""
        with np.errstate(all="ignore"):
            return self._spread(self.tensions(x) - self.rest, lam * r0)

    def residual_mp(self, x, lam: float, r0: np.ndarray, dps: int) -> list:
        """:meth:`residual` in mpmath at ``dps`` digits (λ and G(0) as the float64 numbers they are)."""
        with mpmath.workdps(dps):
            vals = [mp_vector(r, dps) for r in self.values]
            g = [mpmath.mpf(float(lam)) * mpmath.mpf(float(v)) for v in r0]
            for (a, b, F), t0 in zip(self.fmp, self.rest_mp(dps)):
                t = F(self._mp_ext(x, a, b), *vals) - t0
                if a >= 0:
                    g[a] -= t
                if b >= 0:
                    g[b] += t
            return g

    def rest_mp(self, dps: int) -> list:
        """V'(0) of every spring in mpmath (cached per precision)."""
        if dps not in self._rest_mp:
            with mpmath.workdps(dps):
                vals = [mp_vector(r, dps) for r in self.values]
                self._rest_mp[dps] = [F(mpmath.mpf(0), *vals) for _, _, F in self.fmp]
        return self._rest_mp[dps]

    def gradient(self, x) -> np.ndarray:
        g = -self.load_f.copy()
        with np.errstate(all="ignore"):
            for a, b, t in zip(self.a, self.b, self.tensions(x)):
                if a >= 0:
                    g[a] -= t
                if b >= 0:
                    g[b] += t
        return g

    def hessian(self, x) -> np.ndarray:
        H = np.zeros((self.n, self.n))
        with np.errstate(all="ignore"):
            for (a, b, _, _, S), d in zip(self.f64, self.extensions(x)):
                _add(H, a, b, float(S(d, *self.fvals)))
        return H

    def augmented(self, H) -> np.ndarray:
        """H + Σ w wᵀ over free pieces: nonsingular, and its solution keeps each centre of mass."""
        return H + self.w.T @ self.w

    def _mp_ext(self, x, a, b):
        return (x[b] if b >= 0 else 0) - (x[a] if a >= 0 else 0)

    def gradient_mp(self, x, dps: int):
        with mpmath.workdps(dps):
            vals = [mp_vector(r, dps) for r in self.values]
            g = [-mp_vector(v, dps) for v in self.loads]
            for a, b, F in self.fmp:
                t = F(self._mp_ext(x, a, b), *vals)
                if a >= 0:
                    g[a] -= t
                if b >= 0:
                    g[b] += t
            return g

    def stiffness_mp(self, x, dps: int) -> list:
        """V''(d) of every spring at the mpmath positions x, as floats (evaluated at ``dps`` digits)."""
        with mpmath.workdps(dps):
            vals = [mp_vector(r, dps) for r in self.values]
            return [float(S(self._mp_ext(x, a, b), *vals)) for a, b, S in self.smp]

    def hessian_mp(self, x, dps: int):
        """The augmented Hessian in mpmath, an ``mpmath.matrix`` (n, n)."""
        with mpmath.workdps(dps):
            vals = [mp_vector(r, dps) for r in self.values]
            H = mpmath.matrix(self.n, self.n)
            for a, b, S in self.smp:
                _add(H, a, b, S(self._mp_ext(x, a, b), *vals))
            for row in self.w:  # a loop over free pieces
                idx = np.flatnonzero(row)
                for i in idx:
                    for j in idx:
                        H[int(i), int(j)] += mpmath.mpf(float(row[i])) * mpmath.mpf(float(row[j]))
            return H


def _add(H, a: int, b: int, k) -> None:
    """``H += k b bᵀ`` for the spring between a and b (a wall end −1 left out)."""
    for i, si in ((a, -1), (b, 1)):
        for j, sj in ((a, -1), (b, 1)):
            if i >= 0 and j >= 0:
                H[i, j] += si * sj * k


def _cholesky(H: np.ndarray):
    """The Cholesky factor of a symmetric H, or None when H is not (numerically) positive definite."""
    if not np.all(np.isfinite(H)):
        return None
    try:
        return scipy.linalg.cho_factor(H)
    except (np.linalg.LinAlgError, ValueError):
        return None


@dataclass(frozen=True)
class PathEnd:
    """Where the loading path stopped short of the full loads: ``reached`` of them, and why."""

    reached: float
    why: str

    @property
    def fraction(self) -> str:
        """``reached`` as text (``1 − 2.3e-09`` close to 1)."""
        return f"{self.reached:.6g}" if self.reached < 0.999 else f"1 - {1.0 - self.reached:.2g}"


def _stopped(problem: PathProblem, x: np.ndarray, lam: float) -> PathEnd:
    """Why the path ends at x: K's smallest eigenvalue there relative to K's largest at rest, and |x|."""
    size = float(np.max(np.abs(x), initial=0.0))
    with np.errstate(all="ignore"):
        H = problem.augmented(problem.hessian(x))
        H0 = problem.augmented(problem.hessian(np.zeros(problem.n)))
        fine = np.all(np.isfinite(H)) and np.all(np.isfinite(H0))
        ratio = float(np.linalg.eigvalsh(H)[0] / np.linalg.eigvalsh(H0)[-1]) if fine else float("nan")
    return PathEnd(lam, f"there |x| = {size:.3g} and K's smallest eigenvalue is {ratio:.2g} of K's largest at rest: "
                         "beyond, the springs cannot hold the load")


def _beyond(problem: PathProblem, x: np.ndarray, lam: float, r0: np.ndarray) -> bool:
    """Whether the loading path goes on past where float64 stopped: followed in mpmath alone (positions, load
    fraction, K and residual at :meth:`PathProblem.digits` + 20 digits; steps down to 1e-40 of the loads) from
    (x, λ) to λ·(1 + 1e-6). A genuine fold stops it again; a spring giving way to a much softer one within
    float64's resolution of λ (a Toda spring saturating at a relative 1e-15 of the loads) does not."""
    dps = problem.digits(x) + 20
    with mpmath.workdps(dps):
        xs = mpmath.matrix([mpmath.mpf(float(v)) for v in x])
        lam_m, end = mpmath.mpf(lam), mpmath.mpf(lam) * (1 + mpmath.mpf(10) ** -6)
        g0 = mpmath.matrix([mpmath.mpf(float(v)) for v in r0])
        h, floor_h = end - lam_m, mpmath.mpf(10) ** -40 * end

        def soft(p):
            try:
                mpmath.cholesky(problem.hessian_mp(list(p), dps))
            except (ValueError, ZeroDivisionError):
                return None
            ev = mpmath.eigsy(problem.hessian_mp(list(p), dps), eigvals_only=True)
            return min(ev[i] for i in range(problem.n))

        now = soft(xs)
        for _ in range(MAX_PATH):
            if now is None:
                return False
            if lam_m >= end:
                return True
            target = min(end, lam_m + h)
            try:
                pred = xs - (target - lam_m) * mpmath.lu_solve(problem.hessian_mp(list(xs), dps), g0)
            except ZeroDivisionError:  # K singular in mpmath too: a fold
                return False
            nxt, last = pred, None
            for _ in range(2 * MAX_CORRECT):
                if not _inside_mp(problem, list(nxt)):
                    nxt = None
                    break
                try:
                    step = mpmath.lu_solve(problem.hessian_mp(list(nxt), dps),
                                           mpmath.matrix(problem.residual_mp(list(nxt), target, r0, dps)))
                except ZeroDivisionError:
                    nxt = None
                    break
                size = mpmath.norm(step, mpmath.inf)
                if last is not None and size > CONTRACTION * last:
                    nxt = None
                    break
                nxt, last = nxt - step, size
                if size <= mpmath.mpf(10) ** (10 - dps) * max(mpmath.norm(nxt, mpmath.inf), mpmath.mpf(10) ** -300):
                    break
            after = None if nxt is None or not _inside_mp(problem, list(nxt)) else soft(nxt)
            if after is None or after < FOLD_GUARD * now:
                h /= 2
                if h < floor_h:
                    return False
                continue
            xs, lam_m, now = nxt, target, after
            h = min(2 * h, end - lam_m) if lam_m < end else h
    return False


def _correct(problem: PathProblem, x: np.ndarray, lam: float, r0: np.ndarray, scale: float) -> np.ndarray | None:
    """Newton on the loading path's equation at λ (:meth:`PathProblem.residual`) from the predictor ``x``; None
    unless it contracts (each step, or else each residual, at most :data:`CONTRACTION` of the last) and stays
    in the domain.

    Float64 first: converged at a step below ``CORRECT_TOL·scale``, or where the residual reaches float64's
    floor (``RESIDUAL_NOISE`` of the forces at each mass). Otherwise the residual in mpmath (:func:`_correct_mp`):
    a stiff spring's tension formed from float64 positions carries ε·k·|x| of noise, which a soft spring in
    series turns into a displacement error as large as x itself.
    """
    start = x
    prev, prev_g = np.inf, np.inf
    for _ in range(MAX_CORRECT):
        g = problem.residual(x, lam, r0)
        if not np.all(np.isfinite(g)):
            return None
        gmax = float(np.max(np.abs(g)))
        if prev < np.inf and _settled(g, np.maximum(RESIDUAL_NOISE * problem.local_scale(x, lam * r0),
                                                    problem.floor(x, lam * r0, FLOAT_DIGITS))):
            return x
        with np.errstate(all="ignore"):
            try:
                dx = np.linalg.solve(problem.augmented(problem.hessian(x)), g)
            except np.linalg.LinAlgError:
                return None
        size = float(np.max(np.abs(dx), initial=0.0))
        if not np.isfinite(size):
            return None
        if size > CONTRACTION * prev and gmax > CONTRACTION * prev_g:
            break
        cand = x - dx
        if not problem.inside(cand):
            return None
        x, prev, prev_g = cand, size, gmax
        if size <= CORRECT_TOL * scale and _settled(problem.residual(x, lam, r0), np.maximum(
                RESIDUAL_SETTLED * problem.local_scale(x, lam * r0), problem.floor(x, lam * r0, FLOAT_DIGITS))):
            return x
    return _correct_mp(problem, start, lam, r0, scale)


def _inside_mp(problem: PathProblem, xs: list) -> bool:
    """Every extension of the mpmath positions xs inside its potential's domain."""
    for a, b, lo, hi in zip(problem.a, problem.b, problem.lo, problem.hi):
        d = (xs[b] if b >= 0 else 0) - (xs[a] if a >= 0 else 0)
        if not lo < d < hi:
            return False
    return True


def _noise(problem: PathProblem, xs: list, lam: float, r0: np.ndarray, dps: int):
    """How far the residual as evaluated at ``dps`` digits is from its value: the difference to an evaluation
    20 digits finer (a tension written as a difference, a·(1 − exp(−b d)), loses a·10^-digits)."""
    coarse = problem.residual_mp(xs, lam, r0, dps)
    fine = problem.residual_mp(xs, lam, r0, dps + 20)
    with mpmath.workdps(dps + 20):
        return np.array([float(abs(a - b)) for a, b in zip(coarse, fine)])


def _settled(g, bound) -> bool:
    """Every coordinate of the residual g below its ``bound`` (N,): a step that is small next to a large x
    says nothing where a tension is exponential in the extension."""
    return all(abs(v) <= bv for v, bv in zip(g, np.broadcast_to(bound, (len(g),))))


def _correct_mp(problem: PathProblem, x: np.ndarray, lam: float, r0: np.ndarray, scale: float, *,
                float_hessian: bool = True) -> np.ndarray | None:
    """The corrector with the residual at :meth:`PathProblem.digits` digits, the step from the float64 Hessian
    (``float_hessian``) or, where that does not contract or K is ill-conditioned beyond float64, from the
    Hessian in mpmath. Converged at a step below ``CORRECT_TOL·scale``, or where the steps stop contracting
    with the residual below ``10^(8 − digits)`` of the forces at play."""
    dps = problem.digits(x)
    problem.mp_corrections += 1
    if not problem.finite(x):
        return None
    with mpmath.workdps(dps):
        xs = [mpmath.mpf(float(v)) for v in x]
        lu = _lu(problem, x) if float_hessian else None
        floor = problem.floor(x, lam * r0, dps)
        last, last_g = None, None
        for _ in range(2 * MAX_CORRECT):
            g = problem.residual_mp(xs, lam, r0, dps)
            corr = _solve_mp(problem, lu, xs, g, dps)
            if corr is None:
                return None
            cmax, gmax = max(abs(c) for c in corr), max(abs(v) for v in g)
            if not mpmath.isfinite(cmax):
                return None
            if last is not None and cmax > CONTRACTION * last and gmax > CONTRACTION * last_g:
                if _settled(g, np.maximum(floor, 100 * _noise(problem, xs, lam, r0, dps))):
                    return np.array([float(v) for v in xs])
                if lu is None:
                    return None
                lu, last, last_g = None, None, None  # float64's Hessian does not contract: mpmath's
                continue
            xs = [xi - ci for xi, ci in zip(xs, corr)]
            out = np.array([float(v) for v in xs])
            if not (problem.inside(out) and problem.finite(out)):
                # converging in mpmath, but float64's rounding of x leaves the domain or the finite tensions:
                # an extension below float64's resolution of x
                problem.float64_limited |= _inside_mp(problem, xs)
                return None
            last, last_g = cmax, gmax
            if cmax <= CORRECT_TOL * scale and _settled(problem.residual_mp(xs, lam, r0, dps),
                                                        problem.floor(out, lam * r0, dps - 8)):
                return out
    return None


def _tangent(problem: PathProblem, x: np.ndarray, r0: np.ndarray) -> tuple[np.ndarray, bool] | None:
    """``dx/dλ = −K⁻¹ G(0)`` at x and whether K is too ill-conditioned for float64 (then it comes from the
    Hessian in mpmath, as the corrector's steps will); None where K is not positive definite.

    Float64 K loses a soft spring beside a stiff one (1e-10 + 1e6 rounds to 1e6): its condition number
    above :data:`ILL_CONDITIONED`, or a failed float64 Cholesky, sends the solve to mpmath."""
    H = problem.augmented(problem.hessian(x))
    factor = _cholesky(H)
    if factor is not None and np.all(np.isfinite(H)):
        with np.errstate(all="ignore"):
            cond = float(np.linalg.cond(H))
        if cond <= ILL_CONDITIONED:
            return -scipy.linalg.cho_solve(factor, r0), False
    dps = problem.digits(x)
    with mpmath.workdps(dps):
        Hm = problem.hessian_mp([mpmath.mpf(float(v)) for v in x], dps)
        try:
            L = mpmath.cholesky(Hm)
        except (ValueError, ZeroDivisionError):
            return None
        t = mpmath.cholesky_solve(Hm, mpmath.matrix([mpmath.mpf(float(v)) for v in r0])) if L is not None else None
        return np.array([-float(t[i]) for i in range(problem.n)]), True


def _float(f, values) -> float:
    """f(0, *values) as a float (0 where it is not a finite real number)."""
    try:
        v = f(mpmath.mpf(0), *values)
    except (ZeroDivisionError, ValueError, OverflowError, TypeError):
        return 0.0
    if isinstance(v, mpmath.mpc) or not mpmath.isfinite(v):
        return 0.0
    return float(v)


def _first_step(problem: PathProblem, tangent: np.ndarray) -> float:
    """The load step over which every spring stays within the reach of its linearisation at rest: the predicted
    change of its extension at most 0.1 |k2/k3| (or the square root of 0.1 |k2/k4|), k2, k3, k4 the second,
    third and fourth derivatives of V at d = 0; 1 when that reaches the full loads. (A wall spring with
    k2 = 1e-9 beside k3 = 7.5e8 is quadratic from d = 1e-18 on: halving blindly from the full loads would
    take a hundred failed steps.)"""
    rate = np.abs(problem.extensions(tangent))
    h = 1.0
    with np.errstate(all="ignore"):
        for r, (_, _, _, _, S), (k3, k4) in zip(rate, problem.f64, problem.rest_derivatives):
            k2 = abs(float(S(0.0, *problem.fvals)))
            reach = min(0.1 * k2 / abs(k3) if k3 else np.inf, np.sqrt(0.1 * k2 / abs(k4)) if k4 else np.inf)
            if r > 0 and np.isfinite(reach):
                h = min(h, reach / r)
    return max(h, FIRST_STEP) if np.isfinite(h) else 1.0


def _smallest(problem: PathProblem, x: np.ndarray) -> float:
    """K's smallest eigenvalue at x (the augmented K: free pieces' rigid translations lifted): float64's where
    it is resolved (above 1e-8 of the largest), else mpmath's at :meth:`PathProblem.digits`."""
    with np.errstate(all="ignore"):
        H = problem.augmented(problem.hessian(x))
        ev = np.linalg.eigvalsh(H) if np.all(np.isfinite(H)) else np.array([np.nan])
    if np.all(np.isfinite(ev)) and ev[0] > 1e-8 * ev[-1]:
        return float(ev[0])
    dps = problem.digits(x)
    with mpmath.workdps(dps):
        mev = mpmath.eigsy(problem.hessian_mp([mpmath.mpf(float(v)) for v in x], dps), eigvals_only=True)
        return float(min(mev[i] for i in range(problem.n)))


def _predicted(problem: PathProblem, x: np.ndarray, lam_x: float, pred: np.ndarray, nxt: np.ndarray, lam: float,
               r0: np.ndarray) -> bool:
    """The corrector's point agrees with the predictor spring by spring: each extension's correction at most
    :data:`BRANCH` of its predicted change (or of :data:`BRANCH_SHARE` of the largest one), beyond
    :data:`BRANCH_NOISE` of the displacements at its ends (a float64 corrector's noise near a pole) and twice
    the Newton steps still left at both points (the correctors' accuracy, at the residual's floor). A spring whose change is small beside the others' — a light mass hanging on a
    soft spring beside a heavy chain moving a lot — is checked on its own scale: its snap to another branch
    would be lost in the norm of x."""
    d0, dp, dn = problem.extensions(x), problem.extensions(pred), problem.extensions(nxt)
    step = np.abs(dp - d0)
    xe = np.append(np.abs(np.asarray(nxt, dtype=float)), 0.0)
    noise = BRANCH_NOISE * (xe[problem.a] + xe[problem.b])  # what float64 correctors leave (near a pole: more)
    for point, at in ((nxt, lam), (x, lam_x)):  # and what the correctors left: one more Newton step at each point
        with np.errstate(all="ignore"):
            try:
                left = np.linalg.solve(problem.augmented(problem.hessian(point)), problem.residual(point, at, r0))
            except np.linalg.LinAlgError:
                continue
        left = np.append(np.nan_to_num(np.abs(left), nan=0.0, posinf=0.0), 0.0)
        noise = noise + 2.0 * (left[problem.a] + left[problem.b])
    allowed = BRANCH * np.maximum(step, BRANCH_SHARE * float(np.max(step, initial=0.0))) + noise
    return bool(np.all(np.abs(dn - dp) <= allowed))


def _positive(problem: PathProblem, x: np.ndarray, ill: bool) -> bool:
    """K positive definite at x (Cholesky in float64, or in mpmath where K is ill-conditioned for it)."""
    if not problem.inside(x):
        return False
    if not ill:
        return _cholesky(problem.augmented(problem.hessian(x))) is not None
    dps = problem.digits(x)
    with mpmath.workdps(dps):
        try:
            mpmath.cholesky(problem.hessian_mp([mpmath.mpf(float(v)) for v in x], dps))
        except (ValueError, ZeroDivisionError):
            return False
    return True


def _lu(problem: PathProblem, x: np.ndarray):
    """LU factors of the float64 augmented Hessian at x, or None where it is singular or not finite."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)  # singular: handled below, never shown
        try:
            lu = scipy.linalg.lu_factor(problem.augmented(problem.hessian(np.asarray(x, dtype=float))),
                                        check_finite=True)
        except (np.linalg.LinAlgError, ValueError):
            return None
    return lu if np.all(np.isfinite(lu[0])) and np.all(np.diag(lu[0]) != 0) else None


def _solve_mp(problem: PathProblem, lu, xs: list, g: list, dps: int) -> list | None:
    """The Newton correction ``H⁻¹ g`` for the mpmath residual g: by the float64 LU factors ``lu`` (g scaled
    to avoid underflow), or by the mpmath Hessian at xs when ``lu`` is None."""
    gmax = max(abs(v) for v in g)
    if gmax == 0:
        return [mpmath.mpf(0)] * len(g)
    if lu is None:
        try:
            c = mpmath.lu_solve(problem.hessian_mp(xs, dps), mpmath.matrix(g))
        except (ZeroDivisionError, ValueError):
            return None
        return [c[i] for i in range(problem.n)]
    c = scipy.linalg.lu_solve(lu, np.array([float(v / gmax) for v in g]))
    return [gmax * mpmath.mpf(float(ci)) for ci in c]


def path(problem: PathProblem) -> tuple[np.ndarray, int] | PathEnd | None:
    """The stable equilibrium reached by applying ``G(0)`` gradually from rest (module docstring, 2).

    Returns
    -------
    (x, steps)
        The float64 equilibrium at the full loads and the number of load steps taken;
    PathEnd
        where the path ends short of them (K singular, or x running off);
    None
        when x = 0 itself is not stable (K(0) not positive definite): no path starts.
    """
    x = np.zeros(problem.n)
    r0 = problem.gradient(x)
    if not np.all(np.isfinite(r0)):
        return PathEnd(0.0, "the forces at rest are not finite")  # guarded by _at_rest_finite
    found = _tangent(problem, x, r0)
    if found is None:
        return None
    tangent, ill = found
    softest = _smallest(problem, x)
    lam, h, steps = 0.0, _first_step(problem, tangent), 0
    for _ in range(MAX_PATH):  # load steps tried, accepted or halved
        if lam >= 1.0:
            return x, steps
        target = min(1.0, lam + h)
        pred = x + (target - lam) * tangent
        scale = max(float(np.max(np.abs(pred))), float(np.max(np.abs(pred - x))), 1e-300)
        corrector = functools.partial(_correct_mp, float_hessian=False) if ill else _correct
        nxt = corrector(problem, pred, target, r0, scale) if problem.inside(pred) else None
        if nxt is not None and not _predicted(problem, x, lam, pred, nxt, target, r0):
            nxt = None  # the corrector went further than the step predicted: another branch, or too long a step
        ahead = None if nxt is None else _tangent(problem, nxt, r0)  # K positive definite there: the stable branch
        if ahead is not None:  # K's smallest eigenvalue may fall by FOLD_GUARD per step, and K stays positive
            now = _smallest(problem, nxt)  # definite between: a fold is approached, not jumped over
            between = all(_positive(problem, x + c * (nxt - x), ahead[1] or ill) for c in (0.25, 0.5, 0.75))
            ahead = ahead if now >= FOLD_GUARD * softest and between else None
        if ahead is None:
            h = 0.5 * min(h, target - lam)  # (a step clipped at the full loads halves from what it was)
            if h < MIN_STEP * lam or h < FIRST_STEP:
                if lam > 0 and _beyond(problem, x, lam, r0):  # not a fold: float64 cannot follow this path
                    problem.float64_limited = True
                return _stopped(problem, x, lam)
            continue
        x, lam, steps, (tangent, ill), softest = nxt, target, steps + 1, ahead, now
        h = min(1.0, 2.0 * h)
    return PathEnd(lam, f"{MAX_PATH} load steps did not reach the full loads")


def descent(problem: PathProblem) -> np.ndarray | None:
    """A minimum of U by Newton from x = 0 with a Levenberg–Marquardt safeguard (for a scene whose rest
    configuration is not stable); None if it finds none."""
    n = problem.n
    x = np.zeros(n)
    mu = 0.0
    e = problem.energy(x)
    last = np.inf
    for _ in range(MAX_NEWTON):
        g = problem.gradient(x)
        if not np.all(np.isfinite(g)):
            return None
        H = problem.augmented(problem.hessian(x))
        scale = max(np.max(np.abs(np.diag(H))), 1e-300)
        step = None
        for _ in range(60):
            with np.errstate(all="ignore"):
                try:
                    cand = x - np.linalg.solve(H + mu * scale * np.eye(n), g)
                except np.linalg.LinAlgError:
                    mu = max(mu * 10, 1e-8)
                    continue
            ec = problem.energy(cand) if problem.inside(cand) else np.nan
            if np.isfinite(ec) and ec <= e + 1e-12 * abs(e):
                step = cand
                break
            mu = max(mu * 10, 1e-8)
        if step is None:
            return None
        moved = float(np.max(np.abs(step - x)))
        x, e = step, problem.energy(step)
        mu = mu / 10 if mu > 1e-12 else 0.0
        size = max(float(np.max(np.abs(x))), 1e-300)
        if moved <= CORRECT_TOL * size or (mu == 0.0 and moved > 0.5 * last and last <= DESCENT_NOISE * size):
            return x if _cholesky(problem.augmented(problem.hessian(x))) is not None else None
        last = moved if mu == 0.0 else np.inf
    return None


def refine(problem: PathProblem, x: np.ndarray) -> tuple[list, int] | None:
    """x_eq in mpmath, correct to float64, from a float64 approximation: Newton with the residual at
    40, 80, … digits until two precisions agree to :data:`AGREE` per coordinate (relative, or
    absolutely below 1e-40 of the largest) and per spring stiffness V''(d). The correction is solved with
    the float64 Hessian while
    that contracts, else with the Hessian in mpmath. Returns ``(x, digits)`` or None."""
    lu = _lu(problem, x)
    prev, prev_stiff = None, None
    dps = 40
    xs = [mpmath.mpf(float(v)) for v in x]
    while dps <= MAX_DPS:
        with mpmath.workdps(dps):
            xs = [mpmath.mpf(v) for v in xs]
            last = None
            for _ in range(MAX_REFINE):
                g = problem.gradient_mp(xs, dps)
                corr = _solve_mp(problem, lu, xs, g, dps)
                if corr is None:
                    return None
                cmax = max(abs(v) for v in corr)
                if cmax == 0:
                    break
                if not mpmath.isfinite(cmax):
                    return None
                if last is not None and cmax > last / 4:  # not contracting
                    if lu is None:
                        return None
                    lu, last = None, None
                    continue
                xs = [xi - ci for xi, ci in zip(xs, corr)]
                last = cmax
                size = max([abs(v) for v in xs] + [mpmath.mpf(10) ** (-300)])
                if cmax <= size * mpmath.mpf(10) ** (-dps + 8):
                    break
            else:
                return None
            cur = [float(v) for v in xs]
            top = max(max(abs(v) for v in cur), 1e-300)
            stiff = problem.stiffness_mp(xs, dps)  # near a pole V'' rests on the few digits of the distance to it
            if prev is not None and all(abs(p - c) <= max(AGREE * abs(c), 1e-40 * top) for p, c in zip(prev, cur)) \
                    and all(abs(p - c) <= AGREE * abs(c) for p, c in zip(prev_stiff, stiff)):
                return xs, dps
            prev, prev_stiff = cur, stiff
        dps *= 2
    return None


__all__ = ["domain", "path", "descent", "refine", "MAX_DPS", "FIRST_STEP"]
