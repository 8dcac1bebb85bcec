"""Long chains (``[chain]`` scenes): derive one element; its stencil module is rendered by
:mod:`derive.chain_codegen`.

The Lagrangian of a chain is a sum of identical-shaped elements indexed by i:
``T_i = ½ m(i) v_i²`` and ``V_i = ½ k(i) (x_{i+1} − x_i)² [+ ¼ k3(i) (x_{i+1} − x_i)⁴]``.
The Euler–Lagrange equation of an interior mass involves only elements i−1
and i, so it is derived once on that template; the ends (free, wall, ring)
add one boundary row each. The symbolic work and the generated source do not
grow with n: the module applies the template with array slices.

Uniform chains have known closed forms (``m`` and ``k`` free of i)::

    free–free  ω_j² = (4k/m) sin²(jπ/(2n)),          j = 0 … n−1,  shape cos(jπ(i+½)/n)
    wall–wall  ω_j² = (4k/m) sin²(jπ/(2(n+1))),      j = 1 … n,    shape sin(jπ(i+1)/(n+1))
    wall–free  ω_j² = (4k/m) sin²((2j−1)π/(2(2n+1))), j = 1 … n,   shape sin((2j−1)π(i+1)/(2n+1))
    ring       ω_j² = (4k/m) sin²(jπ/n),             j = 0 … n−1,  shapes cos/sin(2πj i/n)
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..generated.contract import End
from .errors import SceneError
from .model import parameter_symbols
from .potential import D, SpringLaw
from .printing import sstr
from .scene import Scene


@dataclass(frozen=True)
class ChainModes:
    """Closed-form spectrum of a uniform chain (None for a non-uniform one)."""

    omega2: sp.Expr | None  # in terms of the mode index j and n
    shape: sp.Expr | None  # in terms of i, j, n
    j_range: tuple[int, str] | None  # (first j, last j as text)
    boundary: str
    notes: tuple[str, ...]
    closed_form: bool = True


class ChainModel:
    """Template derivation of a ``[chain]`` scene."""

    def __init__(self, scene: Scene):
        if scene.chain is None:
            raise ValueError("not a [chain] scene")
        self.scene = scene
        self.chain = scene.chain
        self.params = parameter_symbols(scene)
        self.i = sp.Symbol("i", integer=True, nonnegative=True)
        self.j = sp.Symbol("j", integer=True, nonnegative=True)
        self.n = sp.Symbol("n", integer=True, positive=True)
        sym = {**self.params, "i": self.i}
        self.mass = self.chain.mass.to_sympy(sym)
        #: The spring law V(d) of a potential chain (in i and the parameters), else None.
        self.law = None if self.chain.potential is None else \
            SpringLaw("chain", self.chain.potential.to_sympy({**sym, "d": D}))
        #: Spring stiffness k(i): as written, or V''(0) of a potential (x_eq = 0, see chain_equilibrium).
        self.k = self.chain.k.to_sympy(sym) if self.law is None else sp.factor(self.law.stiffness.subs(D, 0))
        self.k3 = None if self.chain.k3 is None else self.chain.k3.to_sympy(sym)
        # template coordinates x_{i-1}, x_i, x_{i+1}
        # no assumptions: parameters are declared real or positive, so a parameter named x_i
        # (allowed) is a different symbol from the template coordinate x_i
        self.xm, self.x0, self.xp = sp.symbols("x_im1 x_i x_ip1")
        self.v0 = sp.Symbol("v_i")
        # loads: forces on masses named by index, tabulated forces, ground motion
        self.t = sp.Symbol("t", real=True)
        self.g = None if scene.gravity is None else scene.gravity.to_sympy(self.params)
        self.forces = tuple((f.on, f.f.to_sympy({**self.params, "t": self.t}), f.key) for f in scene.forces)
        self.table_forces = tuple((tf.on, tf.key) for tf in scene.table_forces)
        self.ground = None if scene.ground is None or scene.ground.acceleration is None else \
            scene.ground.acceleration.to_sympy({**self.params, "t": self.t})
        # damping: [[dampers]] families/single dashpots (c may use i) and [damping] rayleigh
        self.dampers = tuple((d.kind, d.a, d.b, d.c.to_sympy(sym), d.key) for d in scene.chain_dampers)
        self.rayleigh = None if scene.damping is None or scene.damping.rayleigh is None else \
            tuple(e.to_sympy(self.params) for e in scene.damping.rayleigh)
        #: The tension V'(0) at rest (0 unless the potential pre-stresses the springs); None without a law.
        self.tension = None if self.law is None else chain_equilibrium(self)

    @property
    def linear(self) -> bool:
        """Linear equations: k springs, or a potential quadratic in d with V'(0) = 0."""
        if self.k3 is not None:
            return False
        if self.law is None:
            return True
        deg = self.law.polynomial_degree()
        return deg is not None and deg <= 2 and self.tension == 0


    def mass_at(self, index: int) -> sp.Expr:
        """The mass of chain element ``index``."""
        return self.mass.subs(self.i, index)

    @property
    def ground_motion(self):
        """(v_g, x_g) from the ground acceleration expression (see :attr:`derive.model.Model.ground_motion`)."""
        from .model import integrate_ground

        return None if self.ground is None else integrate_ground(self.ground, self.t)

    def element_potential(self, xa, xb, idx) -> sp.Expr:
        """V of the spring between masses idx and idx+1 (extension xb − xa)."""
        d = xb - xa
        if self.law is not None:
            return self.law.energy.subs(self.i, idx).subs(D, d)
        v = self.k.subs(self.i, idx) * d**2 / 2
        if self.k3 is not None:
            v += self.k3.subs(self.i, idx) * d**4 / 4
        return v

    def interior_equation(self) -> sp.Expr:
        """Force on mass i from elements i−1 and i: ``−∂(V_{i−1} + V_i)/∂x_i``."""
        V = self.element_potential(self.xm, self.x0, self.i - 1) + self.element_potential(self.x0, self.xp, self.i)
        return -sp.diff(V, self.x0)

    @property
    def effects(self) -> tuple[str, ...]:
        return tuple(sorted({"spring", *(["cubic"] if self.k3 is not None else []),
                             *(["potential"] if self.law is not None else []),
                             *(["force"] if self.forces else []), *(["table"] if self.table_forces else []),
                             *(["ground"] if self.scene.ground is not None else []),
                             *(["gravity"] if self.g is not None else []),
                             *(["damper"] if self.dampers else []),
                             *(["rayleigh"] if self.rayleigh is not None else [])}))

    @property
    def rigid_modes(self) -> int:
        return 1 if (self.chain.left is not End.WALL and self.chain.right is not End.WALL) else 0


def _constant_loads(model: ChainModel) -> list[tuple[str, str]]:
    """The scene keys of constant loads, and of the constant part of loads that vary with t
    ('0.5 + 0.5*sin(2*t)': its mean 0.5), as (key, what)."""
    from .forcing import constant_part

    return ([("gravity", "gravity")] if model.g is not None else []) + [
        (key, "force") for _, f, key in model.forces if constant_part(f, model.t) != 0] + (
        [("ground.acceleration", "ground acceleration")]
        if model.ground is not None and constant_part(model.ground, model.t) != 0 else [])


def _refuse_constant_loads(model: ChainModel, springs: str, what_for: str) -> None:
    """One line (SceneError) when a constant load moves the equilibrium of a chain with ``springs``."""
    loads = _constant_loads(model)
    if not loads:
        return
    key, what = loads[0]
    varying = what != "gravity" and (model.ground if key.startswith("ground") else
                                     next(f for _, f, k in model.forces if k == key)).has(model.t)
    raise SceneError(model.scene.file, key, f"a constant load on a chain with {springs}"
                     + (f" (the constant part of the {what})" if varying else "") + " moves its equilibrium away "
                     f"from x = 0{what_for}, which is not supported yet for [chain] scenes; accepted: the same "
                     "scene as [masses] with [[springs]] (solved by Newton), or loads that vary with t "
                     "about a zero mean")


def check_linear_outputs(scene) -> None:
    """:func:`check_modes_apply` for a scene (modes, frf, rsa, state space, sensitivities: every output of
    the linearisation); nothing to check for other scenes."""
    if scene.chain is not None and scene.chain.k3 is not None:
        check_modes_apply(ChainModel(scene))


def check_modes_apply(model: ChainModel) -> None:
    """Refuse (one line) the modes of a chain with cubic springs under a constant load: they are those of
    the linearisation about the static equilibrium, which a [chain] does not solve (about x = 0 they would
    be silently wrong). Its simulation is unaffected (the equations of motion hold the loads)."""
    if model.k3 is not None:
        _refuse_constant_loads(model, "cubic (k3) springs", " (its modes are those about the equilibrium)")


def chain_equilibrium(model: ChainModel) -> sp.Expr:
    """The tension V'(0) of a potential chain at rest, after checking x_eq = 0 is a stable equilibrium.

    x = 0 is the equilibrium when V'(0) = 0 for every spring (no pre-stress), or when the springs
    are all alike and the chain closes on walls at both ends or is a ring: each mass then feels
    V'(0) − V'(0) = 0. Constant loads (gravity, forces free of t) move the equilibrium: such
    scenes, and pre-stressed chains with a free end or an index-dependent V'(0), are refused in one
    line (their equilibrium needs the tension structure along the chain, not done yet). Every
    spring's V, V', V'' must be finite at d = 0 and V''(0) > 0 (the stiffness of the modes).
    """
    from .accurate import exact_values
    from .equilibrium import check_law

    ch, law, file = model.chain, model.law, model.scene.file
    key = "chain.potential"
    tension = sp.simplify(law.force.subs(D, 0))
    _refuse_constant_loads(model, "a potential", "")
    closed = ch.left is End.RING or (ch.left is End.WALL and ch.right is End.WALL)
    if tension != 0 and not (closed and not tension.has(model.i)):
        raise SceneError(file, key, f"V'(0) = {sp.sstr(tension)} is not 0: the springs are pre-stressed at rest, "
                         "and a pre-stressed chain is in equilibrium at x = 0 only between two walls or as a ring "
                         "with the same V'(0) for every spring; accepted: a potential with V'(0) = 0 (d = 0 its "
                         "rest length), or left = right = \"wall\" / \"ring\"")
    subs = exact_values(model.params, model.scene.parameters)
    first = -1 if ch.left is End.WALL else 0
    last = ch.n - 1 if ch.right.has_spring else ch.n - 2
    if not ch.uniform and law.energy.has(model.i):
        _check_chain_stiffness(model, range(first, last + 1), subs)
    else:
        check_law(file, law, sp.Integer(0), subs)
    return tension


def _check_chain_stiffness(model: ChainModel, springs: range, subs: dict) -> None:
    """V, V', V'' finite and V'' > 0 at d = 0 for every spring index (float64, in chunks)."""
    import numpy as np

    from .scene_loader import MAX_MAGNITUDE, MIN_MAGNITUDE

    law = model.law
    values = [float(subs[p]) for p in model.params.values()]
    syms = [model.i] + list(model.params.values())
    for name, expr in (("V", law.energy), ("V'", law.force), ("V''", law.stiffness)):
        f = sp.lambdify(syms, expr.subs(D, 0), "numpy")
        for s in range(springs.start, springs.stop, 1 << 16):
            i = np.arange(s, min(s + (1 << 16), springs.stop), dtype=float)
            with np.errstate(all="ignore"):
                v = np.broadcast_to(np.asarray(f(i, *values), dtype=float), i.shape)
            bad = ~np.isfinite(v) if name != "V''" else ~(v > 0)
            far = (v < MIN_MAGNITUDE) | (v > MAX_MAGNITUDE) if name == "V''" else bad
            if bad.any() or far.any():
                j = int(i[np.argmax(bad | far)])
                why = (f"{name}(0) = {v[np.argmax(bad)]:g} is not finite" if name != "V''" else
                       f"stiffness V''(0) = {v[np.argmax(bad)]:g} is not positive" if bad.any() else
                       f"stiffness V''(0) = {v[np.argmax(far)]:g} is outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} "
                       "(the range of a spring's k)")
                raise SceneError(model.scene.file, "chain.potential", f"{why} for the spring i = {j}; accepted: a "
                                 "potential finite, twice differentiable and with V''(0) > 0 for every spring i")


def chain_modes(model: ChainModel) -> ChainModes:
    ch = model.chain
    left, right = ch.left, ch.right
    if not ch.uniform:
        route = ("the spring-factor route (LDLᵀ of K, one-sided Jacobi SVD; dense, n <= MAX_DENSE)"
                 if left is End.RING else
                 "the singular values of the bidiagonal spring factor (bisection on its Golub–Kahan form)")
        return ChainModes(None, None, None, f"{left}-{right}",
                          (f"non-uniform chain: no closed form; ω² from {route} in the generated module, "
                           "accurate to float64 in the relative sense",), closed_form=False)
    k, m, i, j, n = model.k, model.mass, model.i, model.j, model.n
    c = 4 * k / m
    if left is End.RING:
        return ChainModes(c * sp.sin(sp.pi * j / n) ** 2, sp.cos(2 * sp.pi * j * i / n), (0, "n - 1"),
                          "ring", ("each 0 < j < n/2 appears twice (cos and sin shapes)",))
    if left is End.FREE and right is End.FREE:
        return ChainModes(c * sp.sin(sp.pi * j / (2 * n)) ** 2, sp.cos(sp.pi * j * (i + sp.Rational(1, 2)) / n),
                          (0, "n - 1"), "free-free", ())
    if left is End.WALL and right is End.WALL:
        return ChainModes(c * sp.sin(sp.pi * j / (2 * (n + 1))) ** 2, sp.sin(sp.pi * j * (i + 1) / (n + 1)),
                          (1, "n"), "wall-wall", ())
    # one wall: index from the wall end
    shape = sp.sin((2 * j - 1) * sp.pi * (i + 1) / (2 * n + 1))
    note = () if left is End.WALL else ("wall on the right: i counts from the right end",)
    return ChainModes(c * sp.sin((2 * j - 1) * sp.pi / (2 * (2 * n + 1))) ** 2, shape, (1, "n"),
                      f"{left}-{right}", note)


#: Chains of at most this many masses list every mode in ``modes --json``; longer ones list the
#: first and last MODES_LISTED_EACH_END (with a note).
MAX_MODES_LISTED = 40
MODES_LISTED_EACH_END = 10


def chain_mode_records(model: ChainModel, modes: ChainModes, omega2_values=None,
                       shape_values=None) -> tuple[list[dict], str]:
    """Mode records in the schema of non-chain scenes (``omega2``, ``omega2_value``,
    ``multiplicity``, ``shape``), ascending; for long chains only both ends of the spectrum.

    ``omega2_values`` are the n values of the generated module's ``omega2()`` (needed for a
    non-uniform chain; a uniform one evaluates its closed form). ``shape`` is the closed-form
    shape as a function of the mass index ``i`` (None without a closed form); ``shape_value``
    lists its values only for chains of at most MAX_MODES_LISTED masses: of the closed form, or for a
    chain without one the rows of ``shape_values`` (n × n, ascending ω², from the numeric side:
    :func:`numeric.structural.modal_quantities.chain_mode_shapes`).
    """
    import numpy as np

    n = model.chain.n
    listed = dict(omega2_values) if isinstance(omega2_values, dict) else None  # {position: ω²} of a long chain
    values = None if omega2_values is None or listed is not None else np.asarray(omega2_values, dtype=float)
    order = None
    sub = {model.params[p]: sp.Float(v, 17) if v != int(v) else sp.Integer(int(v))
           for p, v in model.scene.parameters.items()}
    if modes.omega2 is not None:
        lo = modes.j_range[0]
        fam = sp.lambdify(model.j, modes.omega2.subs(sub).subs(model.n, n), "numpy")
        js = np.arange(lo, n + lo, dtype=float)
        fam_values = np.broadcast_to(np.asarray(fam(js), dtype=float), js.shape)
        order = np.argsort(fam_values, kind="stable")
        if values is None:
            values = fam_values[order]
    if listed is not None and values is None:  # only the listed positions (a simple spectrum: open chain)
        values = np.full(n, np.nan)
        values[list(listed)] = np.maximum(np.asarray(list(listed.values()), dtype=float), 0.0)
    elif values is None:
        return [], "modes not listed (the eigen-problem is too large to solve densely here)"
    else:
        values = np.maximum(np.sort(values), 0.0)
    if n <= MAX_MODES_LISTED:
        picked, note = list(range(n)), ""
    else:
        e = MODES_LISTED_EACH_END
        picked = list(range(e)) + list(range(n - e, n))
        note = (f"modes lists the {e} lowest and {e} highest of the {n} modes; "
                + ("the family omega2(j), shape(i, j) gives every one" if modes.omega2 is not None
                   else "the generated module's omega2() gives every one"))
    scale = float(np.nanmax(np.abs(values))) if values.size else 0.0
    records = []
    for p in picked:
        mult = int(np.count_nonzero(np.abs(values - values[p]) <= 1e-12 * max(scale, 1e-300)))
        rec = {"omega2": sp.sstr(sp.Float(values[p], 17)), "omega2_value": float(values[p]),
               "multiplicity": mult, "shape": None}
        if order is not None:
            j = int(order[p]) + modes.j_range[0]
            rec["j"] = j
            rec["omega2"] = sp.sstr(modes.omega2.subs({model.j: j, model.n: n}))
            shape = _record_shape(model, modes, j, n)
            rec["shape"] = sp.sstr(shape)
            if n <= MAX_MODES_LISTED:
                f = sp.lambdify(model.i, shape, "numpy")
                idx = np.arange(n, dtype=float)
                rec["shape_value"] = [float(v) for v in np.broadcast_to(np.asarray(f(idx), dtype=float), (n,))]
        elif shape_values is not None and n <= MAX_MODES_LISTED:
            rec["shape_value"] = [float(v) for v in shape_values[p]]
        records.append(rec)
    return records, note


def _record_shape(model: ChainModel, modes: ChainModes, j: int, n: int) -> sp.Expr:
    """Mode j's shape as an expression of the mass index i (0 at the left end), for one listed mode.

    The family's shape counts i from the wall of a free–wall chain (its note says so): here it is
    turned to the mass index. A ring's ω² of j and n − j are equal and the family's cos(2πji/n) is
    the same for both: the second of the pair (2j > n) takes the independent sin(2πji/n), so the
    listed shapes of a repeated ω² span its eigenspace.
    """
    ch, i = model.chain, model.i
    if ch.left is End.RING and 2 * j > n:
        return sp.sin(2 * sp.pi * j * i / n)
    shape = modes.shape.subs({model.j: j, model.n: n})
    if ch.left is End.FREE and ch.right is End.WALL:
        shape = shape.subs(i, n - 1 - i)
    return shape


def _float64_note(model: ChainModel, records: list[dict]) -> str:
    """A note when listed elastic ω² lie outside float64's normal range (else ``""``).

    Every mass and spring lies in 1e-150 … 1e150, but a long chain's lowest ω² is ~ (k/m)(π/2n)²:
    1e-300 / n² falls below the smallest normal float64 (2.2e-308) past n ~ 7000, where it would
    print with fewer significant digits (subnormal) or as 0. Said, never printed silently.
    """
    from .accurate import FLOAT64_HUGE, FLOAT64_TINY

    ch = model.chain
    rigid = 1 if ch.left is End.RING or (ch.left is End.FREE and ch.right is End.FREE) else 0
    e = MODES_LISTED_EACH_END
    positions = list(range(len(records))) if len(records) == ch.n else list(range(e)) + list(range(ch.n - e, ch.n))
    low = [r["omega2_value"] for r, p in zip(records, positions) if p >= rigid and r["omega2_value"] < FLOAT64_TINY]
    high = [r["omega2_value"] for r in records if not r["omega2_value"] <= FLOAT64_HUGE]
    if not (low or high):
        return ""
    what = (f"{len(low)} listed ω² below {FLOAT64_TINY:.3g} (subnormal: fewer significant digits, or 0)" if low
            else f"{len(high)} listed ω² beyond {FLOAT64_HUGE:.3g}")
    return (f"float64 limit: {what}; these values are not accurate to float64's relative precision "
            "(the spectrum spans more than float64's normal range)")


def _damping_ratios(model: ChainModel, records: list[dict], damped) -> str:
    """Add ``damping_ratio``, ``omega_damped``, ``damping_ratio_expr`` to each listed mode of a damped
    chain (in place, the fields of non-chain scenes) and return a note (empty when every ζ is given).

    ``damped`` holds ``(ω_n, ζ, ω_d)`` of every mode ascending (the dense route of
    ``numeric.modes.chain_damping``, given by the caller) or None: then Rayleigh-only damping takes its
    closed form ζ_j = α/(2ω_j) + βω_j/2 at the listed ω (a sum of positive terms), and dashpots on a
    chain too long for the dense route leave ζ None, said in the note."""
    import math

    n = model.chain.n
    e = MODES_LISTED_EACH_END
    positions = list(range(n)) if len(records) == n else list(range(e)) + list(range(n - e, n))
    alpha = beta = None
    unresolved = 0
    if damped is None and not model.dampers and model.rayleigh is not None:
        sub = {model.params[p]: sp.Rational(v) for p, v in model.scene.parameters.items()}
        alpha, beta = (float(sp.N(c.subs(sub), 30)) for c in model.rayleigh)
    for rec, pos in zip(records, positions):
        zeta = wd = None
        if damped is not None:
            _, zeta, wd = damped[pos]
            if zeta is not None and zeta != zeta:  # NaN: below float64's resolution of the damping
                zeta = None
                unresolved += 1
        elif alpha is not None:
            w = math.sqrt(max(rec["omega2_value"], 0.0))
            if w > 0:
                zeta = alpha / (2 * w) + beta * w / 2
                wd = w * math.sqrt((1 - zeta) * (1 + zeta)) if zeta < 1 else 0.0
        rec.update(damping_ratio=zeta, omega_damped=wd, damping_ratio_expr=None)
    if damped is None and alpha is None:
        return (f"damping ratios not computed: dashpots on a chain of {n} masses (the dense modal "
                "state matrix is used up to 60 masses)")
    if unresolved:
        return (f"damping ratios of {unresolved} modes not given: their decay rate is below 1e-10 of what "
                "float64 resolves in the modal damping (modes all but confined away from every dashpot), and "
                "extended precision did not settle it (it is tried up to 12 masses)")
    return ""


def chain_report(model: ChainModel, modes: ChainModes, omega2_values=None, damped=None,
                 participation=None, shape_values=None) -> tuple[str, dict]:
    """Text and JSON description of a chain's derivation and spectrum.

    The JSON has the top-level shape of non-chain scenes (``scene, parameters, masses, modes,
    closed_form, notes``; ``masses`` is empty: chain masses are indices 0 … n−1) plus the
    chain's ``n, left, right, uniform, j_range`` and its symbolic ``family`` (omega2, shape).
    A damped chain's listed modes carry ``damping_ratio`` and ``omega_damped`` (``damped``: the
    ``(ω_n, ζ, ω_d)`` rows of ``numeric.modes.chain_damping.damped_rows``, see :func:`_damping_ratios`).
    ``participation``: a :class:`~.participation.Participation` of every mode (ascending ω, the
    records' order) for a chain whose supports move, printed and added to the records as for
    ``[masses]`` scenes; without it such a chain gets a note saying where participation is.
    ``shape_values``: the mode shapes of a chain without closed-form modes (see :func:`chain_mode_records`).
    """
    sc, ch = model.scene, model.chain
    force = sp.factor_terms(model.interior_equation())
    lines = [f"Scene {sc.name!r} ({sc.file}): {sc.description}".rstrip(": "),
             f"Chain of n = {ch.n} masses; left end {ch.left}, right end {ch.right}; "
             + ("uniform" if ch.uniform else "index-dependent"),
             "Parameters: " + ", ".join(f"{k} = {sc.parameters[k]:g}" for k in sorted(sc.parameters)),
             "",
             f"Element i:  T_i = {sstr(model.mass * model.v0**2 / 2)}",
             f"            V_i = {sstr(model.element_potential(model.x0, model.xp, model.i))}",
             "Interior equation (Euler-Lagrange on elements i-1 and i):",
             f"    {sstr(model.mass)}*a_i = {sstr(force)}"]
    from .loadgen import chain_load_lines

    lines += chain_load_lines(model)
    from .chain_damping_code import chain_damping_report_lines

    damping_lines, damping_data = chain_damping_report_lines(model, modes)
    lines += damping_lines
    if modes.omega2 is not None:
        lo, hi = modes.j_range
        lines += ["", f"Normal modes ({modes.boundary}, closed form), j = {lo} ... {hi}:",
                  f"    ω_j² = {sstr(modes.omega2)}",
                  f"    shape_j(i) = {sstr(modes.shape)}"]
    law_lines, law_notes, law_data = _law_report(model)
    lines += law_lines
    notes = list(modes.notes) + (["cubic springs: modes of the linearization; no exact solution"]
                                 if model.k3 is not None else []) + law_notes
    lines += [f"    note: {note}" for note in notes]
    records, listed_note = chain_mode_records(model, modes, omega2_values, shape_values)
    zeta_note = _damping_ratios(model, records, damped) if damping_data is not None and records else ""
    if zeta_note:
        notes.append(zeta_note)
    range_note = _float64_note(model, records)
    if range_note:
        notes.append(range_note)
        lines.append(f"    note: {range_note}")
    if records:  # the numbers, for every chain (a closed form or not): as --json lists them
        how = "closed form at the scene's values" if modes.omega2 is not None else \
            "numeric, the generated module's omega2()"
        lines += ["", f"Normal modes ({how}), ascending:"]
        lines += [f"    {'j = ' + str(r['j']) + ':  ' if 'j' in r else ''}ω² = {r['omega2_value']:.10g}"
                  + (f"  (multiplicity {r['multiplicity']})" if r["multiplicity"] > 1 else "")
                  + (f"   zeta = {r['damping_ratio']:.10g}   omega_d = {r['omega_damped']:.10g}"
                     if r.get("damping_ratio") is not None else "") for r in records]
        lines += [f"    note: {zeta_note}"] if zeta_note else []
    lines += [f"    note: {listed_note}"] if listed_note else []
    from .participation import chain_section

    part_lines, part_notes, extra = chain_section(model, participation, records)
    lines, notes = lines + part_lines, notes + part_notes
    data = {"scene": sc.name, "parameters": {k: sc.parameters[k] for k in sorted(sc.parameters)},
            "masses": [], "modes": records, "closed_form": modes.closed_form,
            "notes": notes + ([listed_note] if listed_note else []),
            "n": ch.n, "left": ch.left, "right": ch.right, "uniform": ch.uniform,
            "j_range": None if modes.j_range is None else list(modes.j_range),
            "family": {"omega2": None if modes.omega2 is None else sp.sstr(modes.omega2),
                       "shape": None if modes.shape is None else sp.sstr(modes.shape)}}
    data.update(extra)
    if damping_data is not None:
        data["damping"] = damping_data
    if law_data is not None:
        data["equilibrium"] = law_data
    return "\n".join(lines) + "\n", data


def _law_report(model: ChainModel) -> tuple[list[str], list[str], dict | None]:
    """Text lines, notes and the JSON ``equilibrium`` of a potential chain (nothing otherwise)."""
    law = model.law
    if law is None:
        return [], [], None
    tension = model.tension
    how = ("x = 0: V'(0) = 0, every spring at rest" if tension == 0 else
           f"x = 0: the pre-tension V'(0) = {sstr(tension)} is the same in every spring and balances "
           "at every mass (walls at both ends, or a ring)")
    lines = ["", f"Spring law: V(d) = {sstr(law.energy)}   (d = x_(i+1) - x_i)",
             f"    tension V'(d) = {sstr(law.force)}",
             f"Static equilibrium: {how}",
             f"    stiffness about it k(i) = V''(0) = {sstr(model.k)}   (K = Hessian of V at x_eq)"]
    notes = ["spring potential: modes are those of the linearisation about x_eq = 0 (k = V''(0)); "
             "the exact modal solution does not apply (integrators only)" if not model.linear else
             "spring potential: quadratic in d with V'(0) = 0, i.e. linear springs k = V''(0)"]
    data = {"x": "0", "closed_form": True, "how": how, "potential": sstr(law.energy),
            "tension": sstr(tension), "stiffness": sstr(model.k)}
    return lines, notes, data


__all__ = ["ChainModel", "ChainModes", "chain_modes", "chain_mode_records", "chain_report",
           "MAX_MODES_LISTED", "MODES_LISTED_EACH_END"]
