"""The Lagrangian model of a scene: T, V, R, L, the Euler-Lagrange equations, M, K, C, D.

Every energy term belongs to one scene entry (``masses.m1``, ``springs[0]``,
``dampers[0]``, ``forces[0]``, ``gravity``) and touches at most two
coordinates, so the Euler-Lagrange equations are derived element by element:
the cost grows with the number of entries, not with its square. Only the
effects a scene declares produce terms.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from .errors import SceneError
from .pieces import pieces
from .potential import D, SpringLaw, linear_law
from .scene import WALL, Scene


class Effect(enum.Enum):
    """What kind of scene entry a term comes from."""

    INERTIA = "inertia"
    SPRING = "spring"
    CUBIC = "cubic"
    POTENTIAL = "potential"
    DAMPER = "damper"
    FORCE = "force"
    GRAVITY = "gravity"
    TABLE = "table"
    GROUND = "ground"
    RAYLEIGH = "rayleigh"
    MODAL_DAMPING = "modal_damping"


@dataclass(frozen=True)
class Term:
    """A generalized force on one coordinate, traced to the scene entry that produced it."""

    key: str
    effect: Effect
    coordinate: int
    force: sp.Expr


def parameter_symbols(scene: Scene) -> dict[str, sp.Symbol]:
    """SymPy symbols for the parameters, in sorted order.

    A parameter whose scene value is positive is declared positive, so that
    e.g. ``sqrt(m**2)`` reads ``m``; the generated code is then valid for
    positive values of such parameters (masses and stiffnesses must be
    positive anyway).
    """
    return {
        name: sp.Symbol(name, positive=True) if scene.parameters[name] > 0 else sp.Symbol(name, real=True)
        for name in sorted(scene.parameters)
    }


def integrate_ground(a_g: sp.Expr, t: sp.Symbol) -> tuple[sp.Expr, sp.Expr] | None:
    """``(v_g, x_g)``: the ground acceleration integrated with ``v_g(0) = x_g(0) = 0``, or None
    when SymPy finds no closed form without cases (e.g. a frequency that could be 0)."""
    if not _elementary_in_t(a_g, t):  # e.g. sin(t**2): no elementary integral, and SymPy may take long
        return None
    s = sp.Symbol("_s", real=True)
    try:
        vg = sp.integrate(a_g.subs(t, s), (s, 0, t))
        xg = sp.integrate(vg.subs(t, s), (s, 0, t))
    except (NotImplementedError, ValueError, TypeError):  # pragma: no cover - SymPy gives up
        return None
    if any(e.has(sp.Integral) or e.has(sp.Piecewise) for e in (vg, xg)):
        return None
    vg, xg = sp.expand(vg), sp.expand(xg)  # expanded: no exp(t)*exp(-t) that overflows for large t
    if not all(isinstance(f, (sp.sin, sp.cos, sp.exp)) for e in (vg, xg) for f in e.atoms(sp.Function)):
        return None  # only what the generated module can print with NumPy
    return vg, xg


def _elementary_in_t(expr: sp.Expr, t: sp.Symbol) -> bool:
    """Sums of products of constants, whole powers of t and sin/cos/exp of linear functions of t:
    the forms whose double integral is elementary and quick to find."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Function) and node.has(t):
            if not isinstance(node, (sp.sin, sp.cos, sp.exp)):
                return False
            arg = sp.expand(node.args[0])
            if sp.diff(arg, t).has(t):
                return False
        elif isinstance(node, sp.Pow) and node.has(t):
            if node.exp.has(t) or (node.base.has(t) and not (node.exp.is_Integer and node.exp >= 0)):
                return False
    return True


class Model:
    """Symbolic equations of motion of a (non-[chain]) scene.

    ``M ẍ + C ẋ + K x + f_nl(x) = F(t) + g_force`` with ``M`` diagonal.
    """

    def __init__(self, scene: Scene):
        if scene.chain is not None:
            raise ValueError("a [chain] scene is derived by derive.chain.ChainModel")
        self.scene = scene
        self.params = parameter_symbols(scene)
        self.t = sp.Symbol("t", real=True)
        self.x = tuple(sp.Symbol(f"x_{m}", real=True) for m in scene.mass_names)
        self.v = tuple(sp.Symbol(f"v_{m}", real=True) for m in scene.mass_names)
        self.a = tuple(sp.Symbol(f"a_{m}", real=True) for m in scene.mass_names)
        self.masses = tuple(e.to_sympy(self.params) for e in scene.mass_exprs)
        sym = {**self.params, "t": self.t}
        #: Every spring's law V(d) (k/k3 springs as k d²/2 + k3 d⁴/4), in spring order.
        self.laws = tuple(
            SpringLaw(s.key, s.potential.to_sympy({**self.params, "d": D})) if s.potential is not None
            else linear_law(s.key, s.k.to_sympy(sym), None if s.k3 is None else s.k3.to_sympy(sym))
            for s in scene.springs)
        #: ``(a, b, k, k3, key)`` per spring; for a potential, k is its stiffness V''(d) at the
        #: equilibrium (so K below is the Hessian there) and k3 is None.
        self.springs = tuple(
            (s.a, s.b, None if s.k is None else s.k.to_sympy(sym), None if s.k3 is None else s.k3.to_sympy(sym),
             s.key) for s in scene.springs)
        self.dampers = tuple((d.a, d.b, d.c.to_sympy(sym), d.key) for d in scene.dampers)
        self.forces = tuple((f.on, f.f.to_sympy(sym), f.key) for f in scene.forces)
        self.g = None if scene.gravity is None else scene.gravity.to_sympy(sym)
        #: Tabulated forces as undefined functions ``f_table<j>(t)`` (the table is data, not algebra).
        self.table_forces = tuple((tf.on, sp.Function(f"f_table{tf.key[7:-1]}")(self.t), tf.key)
                                  for tf in scene.table_forces)
        #: Ground acceleration: the expression of t, or None for a table or without [ground].
        self.ground = None if scene.ground is None or scene.ground.acceleration is None else \
            scene.ground.acceleration.to_sympy(sym)
        damping = scene.damping
        #: ``(α, β)`` of Rayleigh damping C = αM + βK ([damping] rayleigh), else None.
        self.rayleigh = None if damping is None or damping.rayleigh is None else \
            tuple(e.to_sympy(sym) for e in damping.rayleigh)
        #: ``((ζ_a, ζ_b), (a, b))`` of ``[damping] rayleigh_targets`` (SymPy ratios, elastic mode numbers), else
        #: None. Its α, β enter as the symbols α_R, β_R (:mod:`derive.rayleigh_targets`).
        self.rayleigh_targets = None if damping is None or damping.targets is None else \
            (tuple(e.to_sympy(sym) for e in damping.targets[0]), damping.targets[1])
        if self.rayleigh_targets is not None:
            from .rayleigh_targets import ALPHA, BETA

            self.rayleigh = (ALPHA, BETA)
        #: Modal damping ratios ζⱼ, one per mode in ascending ω order ([damping] modal), else None.
        self.modal_zeta = None if damping is None or damping.modal is None else \
            tuple(e.to_sympy(sym) for e in damping.modal) * (scene.n if len(damping.modal) == 1 else 1)
        #: The static equilibrium (scenes with potentials, and cubic springs under constant loads; None
        #: otherwise: x = 0, or the linear sag).
        self.equilibrium = self._equilibrium() if scene.has_potential or self._cubic_loaded() else None
        if self.equilibrium is not None:
            self.springs = tuple((a, b, stiff if k is None else k, k3, key) for (a, b, k, k3, key), stiff
                                 in zip(self.springs, self.equilibrium.stiffness))

    def constant_loads(self) -> tuple[list[sp.Expr], list[str]]:
        """The constant force on each coordinate and the scene keys it comes from: gravity ``m g``, the constant
        part of every force (a force free of t, or the constant term of a constant + harmonic one) and of a
        ground acceleration given by an expression (``-m a_g``: coordinates are relative to the ground)."""
        from .forcing import decompose

        def constant(expr):
            if not expr.has(self.t):
                return expr
            parts = decompose(expr, self.t)
            return sp.Integer(0) if parts is None else parts[0]

        loads = [sp.Integer(0)] * self.scene.n
        keys = []
        if self.g is not None:
            loads = [m * self.g for m in self.masses]
            keys.append("gravity")
        for on, f, key in self.forces:
            c = constant(f)
            if c != 0:
                loads[on] += c
                keys.append(key)
        if self.ground is not None:
            c = constant(self.ground)
            if c != 0:
                loads = [ld - m * c for ld, m in zip(loads, self.masses)]
                keys.append("ground.acceleration")
        return loads, keys

    def _cubic_loaded(self) -> bool:
        """Whether a cubic (k3) spring meets a constant load (then its equilibrium is solved as a potential's)."""
        return any(s.k3 is not None for s in self.scene.springs) and any(ld != 0 for ld in self.constant_loads()[0])

    def _equilibrium(self):
        """Solve for the static equilibrium (:func:`derive.equilibrium.solve`), or refuse in one line.

        A cubic (k3) spring away from x = 0 becomes the law it is, ``k d²/2 + k3 d⁴/4`` (its equations of motion
        are the same): the modes are then those of the linearisation about x_eq (K_t = k + 3 k3 d² per spring),
        as for a potential. Without potentials, an equilibrium at x = 0 keeps the cubic springs as they are
        (None: the linearisation about x = 0)."""
        from .equilibrium import solve

        loads, keys = self.constant_loads()
        pieces = [(c, [self.masses[i] for i in c]) for c in self.free_components]
        eq = solve(self.scene.file, self.scene.n, [(a, b, law) for (a, b, *_), law in zip(self.springs, self.laws)],
                   loads, self.params, self.scene.parameters, pieces, load_keys=" and ".join(keys) or "springs")
        if eq.at_rest:
            return eq if self.scene.has_potential else None
        cubic = [j for j, (*_, k3, _) in enumerate(self.springs) if k3 is not None]
        if cubic:
            self.laws = tuple(SpringLaw(law.key, law.energy, given=True, cubic=True) if j in cubic else law
                              for j, law in enumerate(self.laws))
            self.springs = tuple((a, b, None, None, key) if j in cubic else (a, b, k, k3, key)
                                 for j, (a, b, k, k3, key) in enumerate(self.springs))
        return eq

    @property
    def potentials(self) -> tuple[int, ...]:
        """Indices of the springs given by a potential."""
        return tuple(j for j, law in enumerate(self.laws) if law.given)

    @cached_property
    def linear(self) -> bool:
        """Whether the equations are linear: k springs only, or potentials that are quadratic in d with
        V'(0) = 0 (a linear spring written as its energy)."""
        if any(k3 is not None for *_, k3, _ in self.springs):
            return False
        return all(self._quadratic(law) for law in self.laws if law.given)

    @staticmethod
    def _quadratic(law) -> bool:
        deg = law.polynomial_degree()
        return deg is not None and deg <= 2 and sp.simplify(law.force.subs(law.d, 0)) == 0

    # -- energies ------------------------------------------------------------------
    def _ext(self, a: int, b: int, q) -> sp.Expr:
        """Extension of an element between ends a and b (a wall end is 0)."""
        return (q[a] if a != WALL else 0) - (q[b] if b != WALL else 0)

    @cached_property
    def kinetic_terms(self) -> tuple[tuple[str, sp.Expr], ...]:
        return tuple((f"masses.{name}", m * v**2 / 2)
                     for name, m, v in zip(self.scene.mass_names, self.masses, self.v))

    @cached_property
    def potential_terms(self) -> tuple[tuple[str, sp.Expr], ...]:
        terms = []
        for (a, b, k, k3, key), law in zip(self.springs, self.laws):
            d = self._ext(a, b, self.x)
            if law.given:  # V(d) as written, d = x_b - x_a
                terms.append((key, law.energy.subs(law.d, -d)))
                continue
            terms.append((key, k * d**2 / 2 + (k3 * d**4 / 4 if k3 is not None else 0)))
        if self.g is not None:
            terms.append(("gravity", -sum(m * self.g * x for m, x in zip(self.masses, self.x))))
        return tuple(terms)

    @cached_property
    def dissipation_terms(self) -> tuple[tuple[str, sp.Expr], ...]:
        """Rayleigh dissipation terms: one per dashpot and, for ``[damping] rayleigh``, one per mass
        (α m v²/2) and per spring (β k (Δv)²/2), element by element. Modal damping has no
        element form (its C is built from the modes, see :attr:`modal_zeta`)."""
        terms = [(key, c * self._ext(a, b, self.v) ** 2 / 2) for a, b, c, key in self.dampers]
        if self.rayleigh is not None:
            alpha, beta = self.rayleigh
            if alpha != 0:
                terms += [("damping", alpha * m * v**2 / 2) for m, v in zip(self.masses, self.v)]
            if beta != 0:
                terms += [("damping", beta * k * self._ext(a, b, self.v) ** 2 / 2)
                          for a, b, k, _, _ in self.springs]
        return tuple(terms)

    @property
    def T(self) -> sp.Expr:
        return sp.Add(*(e for _, e in self.kinetic_terms))

    @property
    def V(self) -> sp.Expr:
        return sp.Add(*(e for _, e in self.potential_terms))

    @property
    def R(self) -> sp.Expr:
        """Rayleigh dissipation function (0 without dampers)."""
        return sp.Add(*(e for _, e in self.dissipation_terms))

    @property
    def L(self) -> sp.Expr:
        return self.T - self.V

    # -- equations of motion ---------------------------------------------------------
    @cached_property
    def terms(self) -> tuple[Term, ...]:
        """Generalized forces ``-dV/dx_i - dR/dv_i + Q_i``, one per (entry, coordinate)."""
        out: list[Term] = []
        for (a, b, k, k3, key), law in zip(self.springs, self.laws):
            d = self._ext(a, b, self.x)
            if law.given:  # tension V'(d) with d = x_b - x_a: +V' on a, -V' on b
                tension = law.force.subs(law.d, -d)
                out.extend(Term(key, Effect.POTENTIAL, i, sign * tension)
                           for i, sign in ((a, 1), (b, -1)) if i != WALL)
                continue
            for i, sign in ((a, 1), (b, -1)):
                if i == WALL:
                    continue
                out.append(Term(key, Effect.SPRING, i, -sign * k * d))
                if k3 is not None:
                    out.append(Term(key, Effect.CUBIC, i, -sign * k3 * d**3))
        if self.g is not None:
            out.extend(Term("gravity", Effect.GRAVITY, i, m * self.g) for i, m in enumerate(self.masses))
        for a, b, c, key in self.dampers:
            dv = self._ext(a, b, self.v)
            for i, sign in ((a, 1), (b, -1)):
                if i != WALL:
                    out.append(Term(key, Effect.DAMPER, i, -sign * c * dv))
        out.extend(self._damping_model_terms())
        for on, f, key in self.forces:
            out.append(Term(key, Effect.FORCE, on, f))
        for on, f, key in self.table_forces:
            out.append(Term(key, Effect.TABLE, on, f))
        if self.scene.ground is not None:
            a_g = sp.Function("a_g")(self.t)
            out.extend(Term("ground", Effect.GROUND, i, -m * a_g) for i, m in enumerate(self.masses))
        return tuple(out)

    def _damping_model_terms(self) -> list[Term]:
        """``[damping]``: -(αM + βK)v per coordinate (Rayleigh), or -(C_modal v)_i shown as a symbol."""
        n = self.scene.n
        if self.rayleigh is not None:
            alpha, beta = self.rayleigh
            kv = [sp.Integer(0)] * n
            for a, b, k, _, _ in self.springs:
                dv = self._ext(a, b, self.v)
                for i, sign in ((a, 1), (b, -1)):
                    if i != WALL:
                        kv[i] += sign * k * dv
            return [Term("damping", Effect.RAYLEIGH, i, -(alpha * m * v + beta * sp.expand(kv[i])))
                    for i, (m, v) in enumerate(zip(self.masses, self.v))]
        if self.modal_zeta is not None:
            return [Term("damping", Effect.MODAL_DAMPING, i, -sp.Symbol(f"(C_modal*v)_{name}", real=True))
                    for i, name in enumerate(self.scene.mass_names)]
        return []

    @property
    def damped(self) -> bool:
        """Dashpots or a [damping] model: the generated module has a damping matrix."""
        return self.C is not None or self.modal_zeta is not None

    def euler_lagrange(self) -> list[sp.Expr]:
        """``d/dt dL/dv_i - dL/dx_i + dR/dv_i - Q_i`` (= 0 on trajectories), assembled element by element.

        The masses are constants (parameter expressions) and each energy term is a
        quadratic (or quartic) form of one element's extension, so the derivatives
        are known in closed form and no symbolic differentiation is needed:
        ``d/dt dT/dv_i = m_i a_i`` and ``-dV/dx_i - dR/dv_i + Q_i`` is the sum of
        the generalized forces :attr:`terms` on coordinate ``i`` (spring ``-k d``,
        cubic ``-k3 d³``, damper ``-c ḋ``, gravity ``m g``, forces, tables, ground),
        each traced to its scene entry. The result is the same SymPy expression as
        differentiating ``L`` and ``R`` term by term (``tests/symbolic/test_symbolic.py``
        checks it against a hand derivation) at a cost linear in the number of entries.
        """
        lhs = [m * a for m, a in zip(self.masses, self.a)]
        for term in self.terms:
            lhs[term.coordinate] -= term.force
        return lhs

    @cached_property
    def effects(self) -> frozenset[Effect]:
        return frozenset(t.effect for t in self.terms)

    # -- matrices ----------------------------------------------------------------------
    @cached_property
    def M(self) -> sp.Matrix:
        """Mass matrix ``d²T/dv²`` (diagonal for point masses)."""
        return sp.diag(*self.masses)  # d²(m_i v_i²/2)/dv_i² = m_i, one entry per mass

    def _assemble(self, elements, q) -> sp.Matrix:
        n = self.scene.n
        out = sp.zeros(n, n)
        for a, b, c in elements:
            for i, si in ((a, 1), (b, -1)):
                for j, sj in ((a, 1), (b, -1)):
                    if i != WALL and j != WALL:
                        out[i, j] += si * sj * c
        return out

    @cached_property
    def K(self) -> sp.Matrix:
        """Stiffness matrix ``d²V/dx²`` at x = 0 (the linear part of the springs)."""
        return self._assemble([(a, b, k) for a, b, k, _, _ in self.springs], self.x)

    @cached_property
    def C(self) -> sp.Matrix | None:
        """Damping matrix ``d²R/dv²`` of the dashpots and Rayleigh damping (αM + βK); None without
        either. Modal damping is not in it (no closed form: the generated module builds it from
        the accurate modes, see :attr:`modal_zeta`)."""
        if not self.dampers and self.rayleigh is None:
            return None
        C = self._assemble([(a, b, c) for a, b, c, _ in self.dampers], self.v)
        if self.rayleigh is not None:
            alpha, beta = self.rayleigh
            C = C + alpha * self.M + beta * self.K
        return C

    @cached_property
    def D(self) -> sp.Matrix:
        """Dynamical matrix ``M^-1/2 K M^-1/2``."""
        s = [1 / sp.sqrt(m) for m in self.masses]
        n = self.scene.n
        return sp.Matrix(n, n, lambda i, j: self.K[i, j] * s[i] * s[j] if self.K[i, j] != 0 else 0)

    @cached_property
    def gravity_force(self) -> tuple[sp.Expr, ...] | None:
        return None if self.g is None else tuple(m * self.g for m in self.masses)

    def force_expressions(self, *effects: Effect) -> list[sp.Expr]:
        """Sum of the terms of the given effects on each coordinate."""
        out = [sp.Integer(0)] * self.scene.n
        for term in self.terms:
            if term.effect in effects:
                out[term.coordinate] += term.force
        return out

    @cached_property
    def ground_motion(self) -> tuple[sp.Expr, sp.Expr] | None:
        """Ground velocity and displacement ``(v_g, x_g)`` from an acceleration expression,
        integrated with ``v_g(0) = x_g(0) = 0``; None for a table, without [ground], or when
        SymPy finds no closed-form integral."""
        return None if self.ground is None else integrate_ground(self.ground, self.t)

    @cached_property
    def energy(self) -> sp.Expr:
        return self.T + self.V

    @cached_property
    def components(self) -> list[list[int]]:
        """Connected pieces of the spring graph (masses linked by springs), in mass order."""
        return pieces(self.scene.n, ((a, b) for a, b, *_ in self.springs))

    @cached_property
    def free_components(self) -> list[list[int]]:
        """Pieces with no spring to a wall: each has one rigid-body (ω² = 0) mode."""
        walled = {a for a, b, *_ in self.springs if b == WALL} | {b for a, b, *_ in self.springs if a == WALL}
        return [c for c in self.components if not walled.intersection(c)]
