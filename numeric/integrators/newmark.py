"""Newmark-β and HHT-α: the implicit step methods of structural dynamics.

On ``M ẍ + C ẋ + f_int(x) = F(t)`` (here per unit mass: ``a = g(x) + D v + e(t)`` with
``g(x) = −M⁻¹f_int(x)`` the springs (and gravity), ``D = −M⁻¹C``, ``e`` the loads and the ground)
one step of the HHT-α method (Hilber, Hughes & Taylor 1977; α = 0 is Newmark's) is

    x₁ = x₀ + h v₀ + h² ((½ − β) a₀ + β a₁)
    v₁ = v₀ + h ((1 − γ) a₀ + γ a₁)
    a₁ = (1 + α) (g(x₁) + D v₁ + e(t₁)) − α (g(x₀) + D v₀ + e(t₀)),

an implicit equation for a₁. For linear springs it is one linear solve with the matrix
``S = I − (1 + α)(βh² A + γh D)`` (A = −M⁻¹K), factored once per run: a dense LU for
``[masses]`` scenes, a sparse LU of the banded matrix for ``[chain]`` scenes (O(n) per step,
never N × N). Cubic springs are solved by Newton iterations on the residual with the tangent
``A(x) = −M⁻¹Bᵀdiag(k + 3k₃d²)B`` (B the spring incidence, d the extensions).

The parameters are a frozen, self-checking table (:class:`NewmarkParameters`):

* ``newmark`` — average acceleration (trapezoidal rule), γ = ½, β = ¼: second order,
  unconditionally stable, no numerical damping, period elongation θ = 2·atan(ωh/2);
* ``newmark-linear`` — linear acceleration, γ = ½, β = ⅙: second order, stable for
  ωh < 2√3 ≈ 3.46, no numerical damping;
* ``hht`` — α ∈ [−⅓, 0] (default −0.05), γ = (1 − 2α)/2, β = (1 − α)²/4: second order,
  unconditionally stable, numerical damping that grows with ωh (ξ̄ ≈ −α(1 + α)²(ωh)³/8 for small ωh).

The state's ``a`` slot holds the acceleration (and, for α ≠ 0, the force ``g(x) + D v`` of the
step below it, stacked under it: shape (2N, B)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, ClassVar

import numpy as np

from ..errors import RunRefused
from .base import Integrator, Problem, State, StepKernel, finite_positive

#: Newton iterations allowed per step (cubic springs) before the step is refused.
MAX_NEWTON = 30
#: Largest [masses] scene solved with dense LU (larger ones and [chain] scenes: sparse).
DENSE_MAX = 400


@dataclass(frozen=True)
class NewmarkParameters:
    """β, γ, α of the HHT-α family (α = 0: Newmark), checked when built.

    Raises
    ------
    ValueError
        Unless 0 < β, ½ <= γ (no negative numerical damping), −⅓ <= α <= 0, and for α ≠ 0
        γ = (1 − 2α)/2 and β = (1 − α)²/4 (second order and unconditional stability).
    """

    beta: float
    gamma: float
    alpha: float = 0.0

    def __post_init__(self):
        b, g, a = self.beta, self.gamma, self.alpha
        if not (b > 0 and g >= 0.5 and -1.0 / 3.0 <= a <= 0.0):
            raise ValueError(f"Newmark parameters beta = {b}, gamma = {g}, alpha = {a}: accepted: beta > 0, "
                             "gamma >= 1/2, -1/3 <= alpha <= 0")
        if a != 0.0 and not (abs(g - (0.5 - a)) <= 1e-15 and abs(b - 0.25 * (1 - a) ** 2) <= 1e-15):
            raise ValueError(f"HHT alpha = {a}: needs gamma = (1 - 2 alpha)/2 = {0.5 - a} and beta = (1 - alpha)^2/4 "
                             f"= {0.25 * (1 - a) ** 2}; got {g}, {b}")

    @classmethod
    def hht(cls, alpha: float) -> "NewmarkParameters":
        alpha = float(alpha)
        if not (-1.0 / 3.0 <= alpha <= 0.0):
            raise RunRefused(f"hht alpha {alpha!r}: accepted: -1/3 <= alpha <= 0", quantity="alpha")
        return cls(0.25 * (1 - alpha) ** 2, 0.5 - alpha, alpha)

    @property
    def order(self) -> int:
        """2 when γ = ½ + (−α) (Newmark with γ = ½, or HHT), else 1."""
        return 2 if abs(self.gamma - (0.5 - self.alpha)) <= 1e-15 else 1

    @property
    def stability_limit(self) -> float:
        """Largest stable ωh on an undamped oscillator: ∞ when 2β >= γ, else 1/√(γ/2 − β)."""
        if 2 * self.beta >= self.gamma - 1e-15:
            return math.inf
        return 1.0 / math.sqrt(0.5 * self.gamma - self.beta)

    def amplification(self, z: np.ndarray, xi: float = 0.0, dtype=float) -> np.ndarray:
        """The exact one-step map on (x, h·v, h²·a) of ``q̈ + 2ξω q̇ + ω² q = 0`` at z = ωh, shape (..., 3, 3).

        Rows solve the scheme's three equations for the new state (a closed-form 3 × 3 matrix
        per z; its eigenvalues are the method's per-mode propagator). ``dtype=np.longdouble``
        evaluates it in extended precision.
        """
        z = np.asarray(z, dtype=dtype)
        b, g, a = self.beta, self.gamma, self.alpha
        k, c = z**2, 2.0 * xi * z  # (per unit mass, time unit h)
        # unknown a1 (times h²): a1 = (1+α)(−k x1 − c v1) − α(−k x0 − c v0), with
        # x1 = x0 + v0 + (½−β) a0 + β a1 and v1 = v0 + (1−γ) a0 + γ a1 (v in units of h)
        den = 1.0 + (1 + a) * (b * k + g * c)
        # a1 = [ −(1+α)(k(x0 + v0 + (½−β)a0) + c(v0 + (1−γ)a0)) + α(k x0 + c v0) ] / den
        ax = (-(1 + a) * k + a * k) / den
        av = (-(1 + a) * (k + c) + a * c) / den
        aa = (-(1 + a) * (k * (0.5 - b) + c * (1 - g))) / den
        out = np.zeros(z.shape + (3, 3), dtype=dtype)
        out[..., 2, 0], out[..., 2, 1], out[..., 2, 2] = ax, av, aa
        out[..., 0, 0] = 1 + b * ax
        out[..., 0, 1] = 1 + b * av
        out[..., 0, 2] = (0.5 - b) + b * aa
        out[..., 1, 0] = g * ax
        out[..., 1, 1] = 1 + g * av
        out[..., 1, 2] = (1 - g) + g * aa
        return out


@dataclass(frozen=True)
class StructuralOperator:
    """The matrices an implicit step needs, from the scene's spring and dashpot lists.

    Attributes
    ----------
    masses : ndarray, shape (N,)
    spring_ends : ndarray of int, shape (S, 2)
        Mass indices, -1 for a wall.
    stiffness, cubic : ndarray, shape (S,)
        Linear and cubic coefficients (cubic None for linear springs).
    damping : ndarray (N, N), scipy.sparse matrix or None
        ``D = −M⁻¹C``.
    external : callable or None
        ``e(t)`` shape (N,): loads per unit mass and −a_g.
    """

    masses: np.ndarray = field(repr=False)
    spring_ends: np.ndarray = field(repr=False)
    stiffness: np.ndarray = field(repr=False)
    cubic: np.ndarray | None = field(default=None, repr=False)
    damping: object = field(default=None, repr=False)
    external: Callable | None = field(default=None, repr=False)
    sparse: bool = False

    @classmethod
    def from_system(cls, system) -> "StructuralOperator":
        return cls(system.masses, system.spring_ends, system.stiffness, system.cubic_stiffness,
                   system.damping_rate_matrix(),
                   system.external_fn, bool(system.chain or system.n > DENSE_MAX))

    @classmethod
    def from_linear_chain(cls, chain, external=None) -> "StructuralOperator":
        return cls(chain.masses, chain.spring_ends, chain.stiffness, None, None, external,
                   bool(chain.n > DENSE_MAX))

    @property
    def n(self) -> int:
        return int(self.masses.shape[0])

    @cached_property
    def _incidence(self):
        """B as a sparse matrix, or dense for small dense systems (built once)."""
        B = self.incidence()
        return B if self.sparse else B.toarray()

    def incidence(self):
        """B, shape (S, N) sparse: (B x)_s = x_a − x_b for spring s between a and b (walls dropped)."""
        import scipy.sparse

        ends = self.spring_ends
        S = ends.shape[0]
        rows, cols, vals = [], [], []
        for c, sign in ((0, 1.0), (1, -1.0)):
            ok = ends[:, c] >= 0
            rows.append(np.flatnonzero(ok))
            cols.append(ends[ok, c])
            vals.append(np.full(int(ok.sum()), sign))
        return scipy.sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                       shape=(S, self.n))

    def tangent(self, x: np.ndarray | None = None):
        """A(x) = −M⁻¹ Bᵀ diag(k + 3 k₃ d²) B (sparse CSR, or dense for small dense systems; the mean over
        a batch's columns for d²)."""
        import scipy.sparse

        B = self._incidence
        k = self.stiffness
        if self.cubic is not None and x is not None:
            d = B @ x
            k = k + 3.0 * self.cubic * (np.mean(d**2, axis=1) if d.ndim == 2 else d**2)
        if not self.sparse:
            return -(B.T * k[None, :]) @ B / self.masses[:, None]
        return -(scipy.sparse.diags(1.0 / self.masses) @ (B.T @ scipy.sparse.diags(k) @ B)).tocsr()

    def damping_apply(self, v: np.ndarray) -> np.ndarray:
        return 0.0 * v if self.damping is None else self.damping @ v

    def system_matrix(self, A, c1: float, c2: float):
        """``I − c1·A − c2·D`` and its factorisation's solve function."""
        import scipy.sparse

        n = self.n
        D = self.damping
        if self.sparse:
            import scipy.sparse.linalg

            S = scipy.sparse.identity(n, format="csc") - c1 * A
            if D is not None:
                S = S - c2 * (D if scipy.sparse.issparse(D) else scipy.sparse.csr_matrix(D))
            lu = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(S))
            return lambda r: lu.solve(np.asarray(r, dtype=float))
        import scipy.linalg

        Ad = A.toarray() if scipy.sparse.issparse(A) else np.asarray(A)
        S = np.eye(n) - c1 * Ad
        if D is not None:
            S = S - c2 * (D.toarray() if scipy.sparse.issparse(D) else np.asarray(D))
        lu, piv = scipy.linalg.lu_factor(S, check_finite=False)
        getrs = scipy.linalg.get_lapack_funcs("getrs", (lu,))

        def solve(r):
            out, info = getrs(lu, piv, np.asarray(r, dtype=float))
            return out

        return solve


class ProbedOperator:
    """The operator of a bare problem (no spring list): the tangent of ``problem.acceleration`` by
    central differences (dense, N <= DENSE_MAX), always with Newton iterations on the exact
    residual, so the approximate tangent only slows convergence, never changes the step."""

    cubic = True  # "nonlinear": never trust one solve
    damping = None
    sparse = False

    def __init__(self, acceleration, n: int, external=None):
        if n > DENSE_MAX:
            raise RunRefused(f"an implicit step on a bare problem of {n} unknowns: accepted: at most {DENSE_MAX}, "
                             "or a scene's system (for_system)", quantity="method")
        self.acc, self.n, self.external = acceleration, n, external

    def tangent(self, x=None):
        x = np.zeros((self.n, 1)) if x is None else np.asarray(x, dtype=float)[:, :1]
        step = 1e-6 * np.maximum(1.0, np.abs(x[:, 0]))
        cols = np.empty((self.n, self.n))
        for j in range(self.n):  # dense, small problems only
            e = np.zeros((self.n, 1))
            e[j, 0] = step[j]
            cols[:, j] = (self.acc(x + e) - self.acc(x - e))[:, 0] / (2 * step[j])
        return cols

    def damping_apply(self, v):
        return 0.0 * v

    def system_matrix(self, A, c1: float, c2: float):
        return StructuralOperator.system_matrix(self, A, c1, c2)


def _traits(p: NewmarkParameters) -> tuple[int, float, float]:
    """Order, stability limit and force evaluations per step of a parameter set (HHT keeps the
    previous step's force: two evaluations on nonlinear springs, one extra on linear)."""
    return p.order, p.stability_limit, 2.0 if p.alpha != 0.0 else 1.0


class NewmarkFamily(Integrator):
    """HHT-α / Newmark-β step (see the module docstring). Subclasses set :attr:`parameters`.

    Built with :meth:`for_system` it integrates the scene's dampers, loads and ground motion
    itself (no splitting); built bare it needs a linear chain (``problem.linear``).
    """

    parameters: ClassVar[NewmarkParameters]
    order = 2
    symplectic = False
    supports_damping = True
    evals_per_step = 1.0
    #: Keyword settings the class takes (from a run's ``Options.settings``).
    settings: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kw):
        """A subclass's declared traits (order, stability limit, evaluations per step) are those of
        its :attr:`parameters` (read by :meth:`numeric.run.protocol.Traits.of`)."""
        super().__init_subclass__(**kw)
        if "parameters" in cls.__dict__:
            cls.order, cls.stability_limit, cls.evals_per_step = _traits(cls.parameters)

    def __init__(self, operator: StructuralOperator | None = None, parameters: NewmarkParameters | None = None):
        self.operator = operator
        if parameters is not None:
            self.parameters = parameters
        self.order, self.stability_limit, self.evals_per_step = _traits(self.parameters)
        self._counted: list[int] | None = None  # force evaluations of the last kernel's steps

    @classmethod
    def for_system(cls, system, **kw) -> "NewmarkFamily":
        """The method on a :class:`~numeric.system.System` with its damping, loads and ground (no splitting)."""
        return cls(StructuralOperator.from_system(system), **kw)

    # -- the protocol ---------------------------------------------------------------------
    def _operator(self, problem: Problem, n: int | None = None):
        if self.operator is not None:
            return self.operator
        if problem.linear is not None:
            return StructuralOperator.from_linear_chain(problem.linear, problem.external)
        cache = getattr(self, "_probed", None)
        if cache is None or cache[0] is not problem:
            size = n if n is not None else (cache[1].n if cache is not None else None)
            if size is None:
                raise RunRefused(f"method {self.name!r}: call init() before kernel() on a bare problem",
                                 quantity="method")
            cache = (problem, ProbedOperator(problem.acceleration, size, problem.external))
            self._probed = cache
        return cache[1]

    def check(self, problem: Problem) -> None:
        if problem.damping is not None and (self.operator is None or self.operator.damping is None):
            raise RunRefused(f"method {self.name!r}: give the damping through for_system(system)", quantity="method")

    def _external(self, problem: Problem, op: StructuralOperator):
        return op.external if self.operator is not None else problem.external

    def init(self, problem: Problem, x0: np.ndarray, v0: np.ndarray) -> State:
        self.check(problem)
        x0 = np.array(x0, dtype=float)
        v0 = np.array(v0, dtype=float)
        op = self._operator(problem, x0.shape[0])
        f0 = problem.acceleration(x0) + op.damping_apply(v0)
        ext = self._external(problem, op)
        a0 = f0 + (np.reshape(ext(0.0), (-1, 1)) if ext is not None else 0.0)
        return State(x0, v0, np.vstack([a0, f0]) if self.parameters.alpha != 0.0 else a0, 0)

    def kernel(self, problem: Problem, h: float) -> StepKernel:
        h = finite_positive(h)
        self.check(problem)
        op = self._operator(problem)
        p = self.parameters
        b, g, al = p.beta, p.gamma, p.alpha
        acc = problem.acceleration
        ext = self._external(problem, op)
        n = op.n
        c1, c2 = (1 + al) * b * h * h, (1 + al) * g * h
        A = op.tangent()
        solve = op.system_matrix(A, c1, c2)
        hh_pred, h_pred = (0.5 - b) * h * h, (1 - g) * h
        bh2, gh = b * h * h, g * h
        linear = op.cubic is None
        probed = isinstance(op, ProbedOperator)
        counted = self._counted = [0]  # force evaluations made (Newton iterations included)

        def e_at(t):
            return np.reshape(ext(t), (-1, 1)) if ext is not None else 0.0

        def step(x, v, a_state, i):
            a = a_state[:n] if al != 0.0 else a_state
            xt = x + h * v + hh_pred * a
            vt = v + h_pred * a
            const = (1 + al) * e_at((i + 1) * h)
            if al != 0.0:
                const = const - al * (a_state[n:] + e_at(i * h))
            gt = acc(xt)
            rhs = (1 + al) * (gt + op.damping_apply(vt)) + const
            a1 = solve(rhs)
            if not linear:
                a1 = self._newton(op, acc, xt, vt, a1, const, al, bh2, gh, c1, c2, i, None if not probed else solve,
                                  counted)
            x1 = xt + bh2 * a1
            v1 = vt + gh * a1
            counted[0] += 1 if al == 0.0 else 2  # HHT's force at x1: a tangent product on linear springs
            if al == 0.0:
                return x1, v1, a1
            g1 = (gt + bh2 * (A @ a1)) if linear else acc(x1)
            return x1, v1, np.vstack([a1, g1 + op.damping_apply(v1)])

        return step

    @staticmethod
    def _newton(op, acc, xt, vt, a1, const, al, bh2, gh, c1, c2, i, fixed=None, counted=None):
        """Newton's method on R(a) = a − (1+α)(g(x̃ + βh²a) + D(ṽ + γh a)) − const (cubic springs);
        ``fixed``: one factorisation for every iteration (a probed tangent: a chord method);
        ``counted[0]`` grows by the force evaluations made (one per iteration)."""
        scale = max(float(np.max(np.abs(a1))), 1e-300)
        prev = math.inf
        for _ in range(MAX_NEWTON):
            x1, v1 = xt + bh2 * a1, vt + gh * a1
            R = a1 - (1 + al) * (acc(x1) + op.damping_apply(v1)) - const
            if counted is not None:
                counted[0] += 1
            solve = fixed if fixed is not None else op.system_matrix(op.tangent(x1), c1, c2)
            da = solve(R)
            a1 = a1 - da
            scale = max(scale, float(np.max(np.abs(a1))))
            size = float(np.max(np.abs(da)))
            # converged, or stalled at the rounding level (quadratic convergence has ended)
            if size <= 1e-15 * scale or (size <= 1e-11 * scale and size >= 0.25 * prev):
                return a1
            prev = size
        raise RunRefused(f"Newton iterations of the implicit step did not converge at step {i} "
                         f"(cubic springs); accepted: a smaller dt", quantity="dt")

    def evals_for(self, problem: Problem, h: float) -> float:
        return self.evals_per_step

    def force_evals(self, problem: Problem, h: float, steps: int) -> int:
        """The force evaluations the last kernel made (Newton iterations of cubic springs counted
        one by one), the initial one included; the declared count before any kernel ran."""
        if self._counted is None:
            return super().force_evals(problem, h, steps)
        return self.init_evals + self._counted[0]

    def response(self) -> NewmarkResponse:
        """The closed-form per-mode response the planner uses (see :class:`NewmarkResponse`)."""
        return NewmarkResponse(self)

    # -- closed-form per-mode propagator ------------------------------------------------------
    def mode_propagator(self, z, xi: float = 0.0) -> np.ndarray:
        """The (x, h·v, h²·a) one-step matrix on a mode at z = ωh with damping ratio ξ, shape (..., 3, 3)."""
        return self.parameters.amplification(z, xi)


class NewmarkResponse:
    """The per-mode closed-form response of a Newmark/HHT step on ``q̈ = −ω²q``, for the planner.

    The same interface as :class:`numeric.plan.error_models.OscillatorResponse` (whose propagators are
    polynomials in z = ωh; an implicit step's are rational): per step the principal root
    ``ρ e^{iθ}`` of the one-step matrix (:meth:`NewmarkParameters.amplification`), the phase
    defect ``δ = θ − z`` and the shape distortion of the (x, v) map with ``a = −ω²x``.

    * γ = ½ and α = 0 (``newmark``, ``newmark-linear``): ρ = 1 exactly and
      ``tan(θ/2) = (z/2)/√(1 + (β − ¼)z²)``; δ is evaluated without cancellation as
      ``2·atan((u − w)/(1 + uw))`` with u = tan(θ/2), w = tan(z/2) and ``u − w`` from the series of
      ``tan x − x`` (z < π).
    * HHT (α ≠ 0): the characteristic polynomial λ³ − A₁λ² + A₂λ − A₃ of the 3 × 3 matrix in
      extended precision (``np.longdouble``); its real spurious root λ₃ (|λ₃| <= ρ∞ < 1, it dies
      out) by Newton's method, then the principal pair from λ² − (A₁ − λ₃)λ + A₃/λ₃: ρ² = A₃/λ₃,
      θ = atan2(√(ρ² − p²/4), p/2). The shape distortion of HHT (from the spurious root, of
      relative size about 10⁻²z²) is not modelled: it is below the phase error for ωt ≳ 1.
    """

    symplectic = False

    def __init__(self, integrator: "NewmarkFamily"):
        p = integrator.parameters
        self.parameters = p
        self.name = integrator.name
        self.order = int(p.order)
        self.stages = float(integrator.evals_per_step)
        self.stability_limit = float(p.stability_limit)
        if p.alpha != 0.0:  # leading terms δ ≈ c₃z³, ln ρ ≈ c₄z⁴ (used below z = 1e-3, relative error ~1e-4·z²/1e-4)
            lr, th = self._principal(np.array([_SERIES_Z]))
            self._c3 = float((th[0] - np.longdouble(_SERIES_Z)) / np.longdouble(_SERIES_Z) ** 3)
            self._c4 = float(lr[0] / np.longdouble(_SERIES_Z) ** 4)
        self.leading_constant = {0.25: -1.0 / 12.0}.get(p.beta, -1.0 / 24.0) if p.alpha == 0.0 else self._c3

    def stable(self, z):
        return np.asarray(z, dtype=float) < self.stability_limit

    def _principal(self, z):
        """(ln ρ, θ) of the principal pair at z (> 0), in extended precision (see the class docstring)."""
        ld = np.longdouble
        zl = np.asarray(z, dtype=ld)
        M = self.parameters.amplification(zl, dtype=ld)
        A1 = M[..., 0, 0] + M[..., 1, 1] + M[..., 2, 2]
        A2 = (M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0] + M[..., 0, 0] * M[..., 2, 2]
              - M[..., 0, 2] * M[..., 2, 0] + M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
        A3 = (M[..., 0, 0] * (M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
              - M[..., 0, 1] * (M[..., 1, 0] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 0])
              + M[..., 0, 2] * (M[..., 1, 0] * M[..., 2, 1] - M[..., 1, 1] * M[..., 2, 0]))
        lam = np.linalg.eigvals(M.astype(float))
        idx = np.argmin(np.abs(lam.imag) + np.where(np.abs(lam.imag) > 0, 0.0, 0.0)
                        + np.abs(np.abs(lam) - np.min(np.abs(lam), axis=-1, keepdims=True)), axis=-1)
        l3 = np.take_along_axis(lam.real, idx[..., None], axis=-1)[..., 0].astype(ld)
        for _ in range(6):  # Newton on the cubic, from the float64 eigenvalue
            f = ((l3 - A1) * l3 + A2) * l3 - A3
            df = (3 * l3 - 2 * A1) * l3 + A2
            l3 = l3 - f / df
        p = A1 - l3
        q = A3 / l3
        theta = np.arctan2(np.sqrt(np.maximum(q - p * p / 4, 0)), p / 2)
        return 0.5 * np.log(q), theta

    def log_amplitude(self, z):
        z = np.asarray(z, dtype=float)
        if self.parameters.alpha == 0.0:
            return np.zeros_like(z)
        big = self._principal(np.maximum(z, _SERIES_Z / 10))[0].astype(float)
        return np.where(z < _SERIES_Z / 10, self._c4 * z**4, big)

    def angle_defect(self, z):
        z = np.asarray(z, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            if self.parameters.alpha == 0.0:
                c = self.parameters.beta - 0.25
                root = np.sqrt(1.0 + c * z * z)
                u = 0.5 * z / root
                x = 0.5 * z
                # u − w = (z/2)(1/root − 1) − (tan(z/2) − z/2), both parts without cancellation
                tan_minus = np.where(x < 0.5, _tan_minus_x_series(x), np.tan(x) - x)
                diff = x * (-c * z * z) / (root * (1.0 + root)) - tan_minus
                w = np.tan(x)
                small = 2.0 * np.arctan(diff / (1.0 + u * w))
                large = 2.0 * np.arctan(u) - z
                delta = np.where(z < 3.0, small, large)
            else:
                zz = np.maximum(z, _SERIES_Z / 10)
                big = (self._principal(zz)[1] - np.asarray(zz, dtype=np.longdouble)).astype(float)
                delta = np.where(z < _SERIES_Z / 10, self._c3 * z**3, big)
        delta = np.where(z == 0.0, 0.0, delta)
        return np.where(self.stable(z), delta, np.nan)

    def distortion(self, z):
        z = np.asarray(z, dtype=float)
        if self.parameters.alpha != 0.0:
            return np.zeros_like(z), np.zeros_like(z)
        M = self.parameters.amplification(z)
        xx = M[..., 0, 0] - z * z * M[..., 0, 2]
        xv = M[..., 0, 1]
        vv = M[..., 1, 1]
        rho = np.exp(self.log_amplitude(z))
        st = np.sin(z + self.angle_defect(z))
        with np.errstate(invalid="ignore", divide="ignore"):
            s_ = (xx - vv) / (2.0 * rho * st)
            r = z * xv / (rho * st) - 1.0
        small = z < 1e-8
        return np.where(small, 0.0, s_), np.where(small, 0.0, r)


#: Where HHT's response switches to its leading terms (they are fitted at this z).
_SERIES_Z = 1e-2


def _tan_minus_x_series(x):
    """tan x − x = (sin x − x cos x)/cos x with the alternating series Σ (−1)^{k+1} 2k x^{2k+1}/(2k+1)!
    of the numerator (x < 0.5: 14 terms reach full precision, no cancellation)."""
    x = np.asarray(x, dtype=float)
    x2 = x * x
    term = x * x2 / 3.0  # k = 1: 2 x³ / 3!
    total = term.copy()
    for k in range(2, 15):
        # term_k / term_{k-1} = −x² · (k / (k − 1)) / ((2k)(2k + 1))
        term = -term * x2 * (k / (k - 1.0)) / ((2 * k) * (2 * k + 1))
        total = total + term
    return total / np.cos(x)


class NewmarkAverage(NewmarkFamily):
    """Newmark's average-acceleration method (trapezoidal rule): γ = ½, β = ¼."""

    name = "newmark"
    parameters = NewmarkParameters(0.25, 0.5)


class NewmarkLinear(NewmarkFamily):
    """Newmark's linear-acceleration method: γ = ½, β = ⅙ (stable for ωh < 2√3)."""

    name = "newmark-linear"
    parameters = NewmarkParameters(1.0 / 6.0, 0.5)


class HHTAlpha(NewmarkFamily):
    """The Hilber–Hughes–Taylor α method, α ∈ [−⅓, 0] (default −0.05)."""

    name = "hht"
    settings = ("alpha",)
    DEFAULT_ALPHA: ClassVar[float] = -0.05
    parameters = NewmarkParameters.hht(DEFAULT_ALPHA)

    def __init__(self, operator: StructuralOperator | None = None, alpha: float | None = None):
        super().__init__(operator, None if alpha is None else NewmarkParameters.hht(alpha))


__all__ = ["NewmarkParameters", "NewmarkResponse", "StructuralOperator", "NewmarkFamily", "NewmarkAverage", "NewmarkLinear", "HHTAlpha"]
