"""Render a derived ``[masses]`` model as a plain NumPy module (a string; writing is separate).

The text is a pure function of the scene: parameters in sorted order, no
timestamps, no versions, SymPy's printer for every expression. No scene text
reaches the source except validated identifiers (scene, mass and parameter
names) and numbers printed by SymPy. Each function takes the parameters as
keyword arguments, so one module serves any parameter values.

The module is :func:`derive.module_text.module_head` (the header every generated module
shares) followed by the section writers in :data:`SECTIONS`, one per concern: constants,
element constants, matrices, spectrum, acceleration, damping, forces, gravity, tables and
ground, energy. Each is a function ``(context) -> list[str]`` of a :class:`_Context` that
returns nothing when the scene does not declare its effect.

Adding an effect (see STYLE.md: a scene type, its Lagrangian term, its section writer, the
contract entry numeric reads) touches this file in one place: write ``_my_effect(c)`` returning
the lines of its functions (:func:`derive.module_text.function` writes one) and put it in
:data:`SECTIONS` where its functions belong; effect writers shared with ``[chain]`` modules live
in their own module (:mod:`derive.loadgen`, :mod:`derive.damping_code`) and are listed the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import sympy as sp

from .codeprint import array, matrix, p
from .damping_code import damping_matrix_lines, matrix_damping_acceleration_lines
from .forcing import harmonic_table
from .loadgen import ground_lines, table_force_lines
from .model import Effect, Model
from .module_text import function, module_head, pasted, render
from .modes import ModeSet
from .potential_code import (dense_acceleration_lines, dense_energy_lines, dense_law_lines,
                             dense_spring_constant_lines)
from .spring_factor import helper_source
from .bands.codegen import band_section
from .stable_forms import stable_closed_forms

#: Scenes with more masses get matrices assembled from the spring list, not printed entry by entry.
MAX_PRINTED_MATRIX = 12


@dataclass(frozen=True)
class _Context:
    """What every section writer of a ``[masses]`` module reads (built once per render)."""

    model: Model
    modes: ModeSet
    _printed: dict = field(default_factory=dict, repr=False, compare=False)

    @cached_property
    def params(self) -> tuple[str, ...]:
        return tuple(self.model.params)  # sorted

    @cached_property
    def sig(self) -> str:
        """The parameters as a signature: ``c, k, m``."""
        return ", ".join(self.params)

    @cached_property
    def kw(self) -> str:
        """The signature after a leading argument: ``, c, k, m`` (empty without parameters)."""
        return (", " + self.sig) if self.params else ""

    @cached_property
    def kwcall(self) -> str:
        """The parameters passed on: ``c=c, k=k, m=m``."""
        return ", ".join(f"{q}={q}" for q in self.params)

    @cached_property
    def dense(self) -> bool:
        """Whether matrices and per-mass expressions are printed (else assembled from element lists)."""
        return self.model.scene.n <= MAX_PRINTED_MATRIX

    @cached_property
    def stable(self):
        """Float64-stable closed forms ``(omega2, shapes)``, or None (then the spring-factor helper)."""
        return stable_closed_forms(self.modes)

    @cached_property
    def cubic(self) -> bool:
        return any(k3 is not None for *_, k3, _ in self.model.springs)

    @cached_property
    def laws(self) -> bool:
        """Spring potentials (then the equilibrium is solved: :mod:`derive.equilibrium`)."""
        return self.model.equilibrium is not None

    @cached_property
    def accurate_helper(self) -> bool:
        """Whether the module carries ``_accurate_modes()`` (and so imports scipy.linalg)."""
        return self.stable is None or self.model.modal_zeta is not None

    @cached_property
    def _private(self) -> dict:
        # coordinates print under private names (_x_m1), so no parameter can shadow them
        return {s: sp.Symbol("_" + s.name, **s.assumptions0) for s in (*self.model.x, *self.model.v)}

    def p(self, expr) -> str:
        """Print once per distinct expression (a long uniform chain repeats ``m`` and ``k``)."""
        text = self._printed.get(expr)
        if text is None:
            text = self._printed[expr] = p(expr.xreplace(self._private) if isinstance(expr, sp.Basic) else expr)
        return text

    def unpack(self, symbols) -> str:
        """``_x_m1, _x_m2 = _x``'s left side for coordinates ``symbols``."""
        return ", ".join("_" + str(s) for s in symbols) + ("," if len(symbols) == 1 else "")

    def per_mass(self, exprs, *, skip_zero: bool = False) -> list[str]:
        """``_out[i] = expr_i / m_i`` for each mass (the printed per-mass form)."""
        return [f"    _out[{i}] = {self.p(e / m)}" for i, (e, m) in enumerate(zip(exprs, self.model.masses))
                if not (skip_zero and e == 0)]


def _doc(model: Model) -> str:
    return (f"Equations of motion and normal modes of scene {model.scene.name!r}.\n\n"
            "Coordinates are displacements from the springs' rest configuration, in the order\n"
            "of MASS_NAMES; arrays of states have shape (N, ...) (a batch in trailing axes).\n"
            "Every function takes the parameters PARAMETERS as keyword arguments.\n")


# -- sections ----------------------------------------------------------------------------------
def _constants(c: _Context) -> list[str]:
    """The scene's shape: masses, effects, element ends, closed form, rigid pieces."""
    model, sc = c.model, c.model.scene
    dampers = (["#: Damper ends as mass indices; -1 is a wall.",
                f"DAMPER_ENDS = {tuple((a, b) for a, b, *_ in model.dampers)!r}"] if model.dampers else [])
    return [f"MASS_NAMES = {tuple(sc.mass_names)!r}",
            f"N = {sc.n}",
            f"EFFECTS = {tuple(sorted(e.value for e in model.effects))!r}",
            f"LINEAR = {model.linear!r}",
            "#: Spring ends as mass indices; -1 is a wall.",
            f"SPRING_ENDS = {tuple((a, b) for a, b, *_ in model.springs)!r}",
            *dampers,
            f"CLOSED_FORM = {c.modes.closed_form!r}",
            f"RIGID_MODES = {len(model.free_components)}",
            "#: Mass indices of each free piece (no spring to a wall): one rigid-body mode each.",
            f"RIGID_PIECES = {tuple(tuple(sorted(piece)) for piece in model.free_components)!r}"]


def _element_constants(c: _Context) -> list[str]:
    """masses(), spring_constants() and, when declared, cubic_constants() and damper_constants()."""
    model = c.model
    out = function(f"masses({c.sig})", "Masses, shape (N,).", [f"    return {array([c.p(m) for m in model.masses])}"])
    numeric_k = dense_spring_constant_lines(model, c.sig, c.kwcall) if c.laws else None
    out += function(f"spring_constants({c.sig})", "Linear stiffness of each spring in SPRING_ENDS order, shape (S,)"
                    + (" (potentials: V''(d) at the equilibrium)." if c.laws else "."),
                    numeric_k or [f"    return {array([c.p(k) for _, _, k, _, _ in model.springs])}"])
    if c.cubic:
        k3s = [c.p(k3 if k3 is not None else 0) for *_, k3, _ in model.springs]
        out += function(f"cubic_constants({c.sig})", "Cubic coefficient k3 of each spring (0 where linear), shape (S,).",
                        [f"    return {array(k3s)}"])
    if model.dampers:
        out += function(f"damper_constants({c.sig})",
                        "Damping coefficient of each damper in DAMPER_ENDS order, shape (D,).",
                        [f"    return {array([c.p(d) for _, _, d, _ in model.dampers])}"])
    return out


def _mass_and_stiffness(c: _Context) -> list[str]:
    """mass_matrix() and stiffness_matrix(): printed, or assembled past MAX_PRINTED_MATRIX masses."""
    m = matrix(c.model.M) if c.dense else f"numpy.diag(masses({c.kwcall}))"
    k = matrix(c.model.K) if c.dense else f"_assemble(_SPRING_ENDS, spring_constants({c.kwcall}))"
    return (function(f"mass_matrix({c.sig})", "M = d²T/dv², shape (N, N).", [f"    return {m}"])
            + function(f"stiffness_matrix({c.sig})", "K = d²V/dx² at x = 0, shape (N, N).", [f"    return {k}"]))


def _damping_matrix(c: _Context) -> list[str]:
    """damping_matrix() and its coefficients (:mod:`derive.damping_code`), for damped scenes."""
    if not c.model.damped:
        return []
    return damping_matrix_lines(c.model, c.sig, c.kwcall, matrix if c.dense else None)


def _dynamical_matrix(c: _Context) -> list[str]:
    """dynamical_matrix() and, past MAX_PRINTED_MATRIX masses, the element assembler _assemble()."""
    if c.dense:
        return function(f"dynamical_matrix({c.sig})", "D = M^-1/2 K M^-1/2, shape (N, N).",
                        [f"    return {matrix(c.model.D)}"])
    return (function(f"dynamical_matrix({c.sig})", "D = M^-1/2 K M^-1/2, shape (N, N).",
                     [f"    _r = 1.0 / numpy.sqrt(masses({c.kwcall}))",
                      f"    return stiffness_matrix({c.kwcall}) * _r[:, None] * _r[None, :]"])
            + function("_assemble(ends, values)",
                       "Σ_e c_e b_e b_eᵀ over elements with ends (a, b) (-1 = wall): an (N, N) matrix.",
                       ["    _ends = numpy.asarray(ends, dtype=numpy.intp).reshape(-1, 2)",
                        "    _out = numpy.zeros((_N, _N))",
                        "    for _ci, _si in ((0, 1.0), (1, -1.0)):",
                        "        for _cj, _sj in ((0, 1.0), (1, -1.0)):",
                        "            _ok = (_ends[:, _ci] >= 0) & (_ends[:, _cj] >= 0)",
                        "            numpy.add.at(_out, (_ends[_ok, _ci], _ends[_ok, _cj]), _si * _sj * values[_ok])",
                        "    return _out"]))


def _spectrum(c: _Context) -> list[str]:
    """omega2() and mode_shapes(): stable closed forms, or the spring-factor helper's values."""
    if c.stable is not None:
        omega2, cols = c.stable
        shapes = sp.Matrix(c.model.scene.n, len(cols), lambda i, j: cols[j][i])
        return (function(f"omega2({c.sig})",
                         "Closed-form squared angular frequencies, one per independent mode, shape (N,).\n\n"
                         "Ordered by value at DEFAULTS; repeated values appear once per shape. Every expression\n"
                         "is free of cancellation (no sum of terms of both signs), so it is accurate to a few\n"
                         "ulps at any positive parameter values.\n",
                         [f"    return {array([c.p(e) for e in omega2])}"])
                + function(f"mode_shapes({c.sig})",
                           "Closed-form physical mode shapes as columns, in omega2() order, shape (N, N); any scale.",
                           [f"    return {matrix(shapes)}"]))
    why = ("the closed forms cancel in float64 at some parameter values (radicals, trigonometric "
           "roots or sums of both signs)" if c.modes.closed_form else "no closed form")
    call = f"_accurate_modes(masses({c.kwcall}), spring_constants({c.kwcall}))"
    return (function(f"omega2({c.sig})",
                     "Squared angular frequencies, ascending, rigid modes exactly 0 first, shape (N,).\n\n"
                     f"Computed numerically ({why}) by the accurate spring-factor route _accurate_modes():\n"
                     "correct to float64 in the relative sense at any positive parameter values.\n",
                     [f"    return {call}[0]"])
            + function(f"mode_shapes({c.sig})",
                       "Physical, M-orthonormal mode shapes as columns in omega2() order, shape (N, N).\n\n"
                       f"Computed numerically ({why}) by _accurate_modes().\n",
                       [f"    return {call}[1]"]))


def _spectrum_helper(c: _Context) -> list[str]:
    """The spring-factor helper's source, for a scene without stable closed forms or with modal damping."""
    return pasted(helper_source()) if c.accurate_helper else []


_ACCELERATION_DOC = """.

Parameters
----------
x : ndarray, shape (N, ...)
    Displacements; trailing axes are a batch of states.

Returns
-------
ndarray, shape (N, ...)
"""


def _acceleration(c: _Context) -> list[str]:
    """acceleration(x): springs (linear and cubic) and gravity, per mass or by the spring list."""
    model = c.model
    doc = "Acceleration from springs" + (" and gravity" if model.g is not None else "") + _ACCELERATION_DOC
    if c.laws:  # spring potentials: their tensions summed on the masses (derive.potential_code)
        body = dense_acceleration_lines(model, c.kwcall)
    elif c.dense:
        cons = model.force_expressions(Effect.SPRING, Effect.CUBIC, Effect.GRAVITY)
        body = [f"    {c.unpack(model.x)} = _x", "    _out = numpy.empty(numpy.shape(_x))",
                *c.per_mass(cons), "    return _out"]
    else:  # incidence form: one pass over the spring list, no N expressions
        body = _incidence_lines(c, "_x", "_SPRING_ENDS", "spring_constants", cubic=True)
        if model.g is not None:
            body.append(f"    _f += gravity_forces({c.kwcall}).reshape(_col)")
        body.append(f"    return _f / masses({c.kwcall}).reshape(_col)")
    return function(f"acceleration(_x{c.kw})", doc, body)


#: Effects whose forces the scalar writer emits, one ``+=`` line per mass and effect (a new force
#: term -- a potential -- is one more entry here). Springs, cubic terms and gravity form the first line.
_SCALAR_EFFECTS = ((Effect.SPRING, Effect.CUBIC, Effect.GRAVITY), (Effect.FORCE,), (Effect.GROUND,))

_SCALAR_DOC = """a(x) + a_ext(t) as straight-line scalar code (springs, cubic terms, gravity, expression forces,
ground acceleration), written into ``_out``: compiled by numeric (numba) for the small-scene loops.

Parameters
----------
_x : ndarray, shape (N,)
t : float
_out : ndarray, shape (N,)
    Overwritten with the acceleration.
_p : ndarray, shape (P,)
    The parameter values in PARAMETERS order.
"""


def _scalar_force(c: _Context) -> list[str]:
    """scalar_force(x, t, out, p): the per-mass forces over scalars (no NumPy calls on arrays), for
    scenes printed per mass. Damping is not in it: the loops take -M⁻¹C as a matrix (Strang splitting)."""
    model = c.model
    if not c.dense:
        return []
    call = ", ".join(["_x", "t", "_out"] + [f"_p[{j}]" for j in range(len(c.params))])
    outer = [f"    _scalar_force_terms({call})  # the parameters in PARAMETERS order"]
    body = [f"    _{s} = _x[{i}]" for i, s in enumerate(model.x)]
    first = True
    helpers: list[str] = []
    if c.laws:  # spring potentials: one tension line per spring (stable forms), summed on the masses
        lines, helpers = _scalar_tension_lines(model, c)
        body += lines
        first = False
    for group in _SCALAR_EFFECTS:
        if c.laws and Effect.SPRING in group:
            continue
        if group == (Effect.GROUND,) and model.ground is None:  # a ground table: data at run time
            continue
        exprs = model.force_expressions(*group)
        if model.ground is not None:  # the ground term's a_g(t) stands for the scene's expression
            exprs = [e.xreplace({sp.Function("a_g")(model.t): model.ground}) for e in exprs]
        if not first and all(e == 0 for e in exprs):
            continue
        op = "=" if first else "+="
        body += [f"    _out[{i}] {op} {c.p(e / m)}" for i, (e, m) in enumerate(zip(exprs, model.masses))
                 if first or e != 0]
        first = False
    out = (function("scalar_force(_x, t, _out, _p)", _SCALAR_DOC, outer)
           + function(f"_scalar_force_terms(_x, t, _out{c.kw})",
                      "scalar_force() with the parameters as arguments (the body numba compiles).", body))
    if helpers:
        from .law_helpers import helper_source

        out += ["", "", *helper_source(helpers).rstrip("\n").split("\n")]
    return out


def _scalar_tension_lines(model, c: _Context) -> tuple[list[str], list[str]]:
    """Lines ``_d<j> = x_b - x_a``, ``_t<j> = V'(_d<j>)`` (the stable forms of derive.stable_laws, as the
    NumPy ``spring_tensions``), then ``_out[i] = (Σ ±_t<j> + m_i g) / m_i``; and the scalar helpers they call."""
    from .law_helpers import SCALAR
    from .potential import D
    from .potential_code import dense_law_exprs, scalar_helper_names

    tensions = dense_law_exprs(model)[0]
    lines = []
    sums = [sp.Integer(0)] * len(model.masses)
    for j, ((a, b, *_), tension) in enumerate(zip(model.springs, tensions)):
        end = lambda i: 0 if i < 0 else model.x[i]  # noqa: E731  (a wall is at 0)
        lines.append(f"    _d{j} = {c.p(end(b) - end(a))}")
        text = c.p(tension.xreplace({D: sp.Symbol(f"_d{j}")}))
        for name, scalar in SCALAR.items():
            text = text.replace(f"{name}(", f"{scalar}(")
        lines.append(f"    _t{j} = {text}")
        tj = sp.Symbol(f"_t{j}")
        if a >= 0:
            sums[a] += tj
        if b >= 0:
            sums[b] -= tj
    gravity = model.force_expressions(Effect.GRAVITY)
    lines += [f"    _out[{i}] = {c.p((s + g) / m)}" for i, (s, g, m) in enumerate(zip(sums, gravity, model.masses))]
    return lines, scalar_helper_names(tensions)


def _incidence_lines(c: _Context, arg: str, ends: str, constants: str, *, cubic: bool,
                     forces: bool = True) -> list[str]:
    """Body lines that form the element extensions ``_d`` (shape (S, ...)) of ``arg`` over an element
    list and, with ``forces``, the summed element forces ``_f`` (shape (N, ...)); ``_col`` reshapes a
    per-mass or per-element vector against the batch axes. Used past MAX_PRINTED_MATRIX masses."""
    out = [f"    {arg} = numpy.asarray({arg}, dtype=_float)",
           f"    _col = (-1,) + (1,) * ({arg}.ndim - 1)",
           f"    _ends = numpy.asarray({ends}, dtype=numpy.intp).reshape(-1, 2)",
           "    _a, _b = _ends[:, 0], _ends[:, 1]",
           f"    _xe = numpy.concatenate([{arg}, numpy.zeros((1,) + {arg}.shape[1:])])  # row -1 = wall",
           "    _d = _xe[_a] - _xe[_b]"]
    if not forces:
        return out
    out.append(f"    _s = {constants}({c.kwcall}).reshape(_col) * _d")
    if cubic and c.cubic:
        out.append(f"    _s = _s + cubic_constants({c.kwcall}).reshape(_col) * _d**3")
    return out + [f"    _f = numpy.zeros({arg}.shape)",
                  "    _ia, _ib = numpy.flatnonzero(_a >= 0), numpy.flatnonzero(_b >= 0)",
                  "    numpy.add.at(_f, _a[_ia], -_s[_ia])",
                  "    numpy.add.at(_f, _b[_ib], _s[_ib])"]


def _bound_acceleration(c: _Context) -> list[str]:
    """make_acceleration(): acceleration() with the parameters bound (linear: -M⁻¹K formed once)."""
    if not c.model.linear:
        call = f"acceleration(_y{', ' + c.kwcall if c.kwcall else ''})"
        return function(f"make_acceleration({c.sig})",
                        "acceleration() with the parameters bound (nonlinear springs: the expressions above).",
                        ["", "    def _bound(_y):", f"        return {call}", "", "    return _bound"])
    g = c.model.g is not None
    doc = "acceleration() with the parameters bound: -M⁻¹K" + (" and g" if g else "") + \
        " formed once; x shape (N,) or (N, B)."
    body = [f"    _inv_m = 1.0 / masses({c.kwcall})"]
    body += _bound_by_elements(c, g) if not c.dense else _bound_by_matrix(c, g)
    return function(f"make_acceleration({c.sig})", doc, body + ["", "    return _bound"])


def _bound_by_matrix(c: _Context, g: bool) -> list[str]:
    out = [f"    _A = -_inv_m[:, None] * stiffness_matrix({c.kwcall})"]
    if not g:
        return out + ["", "    def _bound(_y):", "        return _A @ _y"]
    return out + [f"    _g = (_inv_m * gravity_forces({c.kwcall}))[:, None]", "",
                  "    def _bound(_y):", "        return _A @ _y + (_g if numpy.ndim(_y) == 2 else _g[:, 0])"]


def _bound_by_elements(c: _Context, g: bool) -> list[str]:
    """The incidence form: one pass over the spring list, no N x N matrix."""
    col = "reshape((-1,) + (1,) * (_x.ndim - 1))"
    return ["    _ends = numpy.asarray(_SPRING_ENDS, dtype=numpy.intp).reshape(-1, 2)",
            "    _a, _b = _ends[:, 0], _ends[:, 1]",
            f"    _k = spring_constants({c.kwcall})",
            "    _ia, _ib = numpy.flatnonzero(_a >= 0), numpy.flatnonzero(_b >= 0)",
            *([f"    _g = _inv_m * gravity_forces({c.kwcall})"] if g else []),
            "",
            "    def _bound(_y):",
            "        _x = numpy.asarray(_y, dtype=float)",
            "        _xe = numpy.concatenate([_x, numpy.zeros((1,) + _x.shape[1:])])  # row -1 = wall",
            f"        _s = _k.{col} * (_xe[_a] - _xe[_b])",
            "        _f = numpy.zeros_like(_x)",
            "        numpy.add.at(_f, _a[_ia], -_s[_ia])",
            "        numpy.add.at(_f, _b[_ib], _s[_ib])",
            f"        _f *= _inv_m.{col}",
            *([f"        _f += _g.{col}"] if g else []),
            "        return _f"]


def _damping_acceleration(c: _Context) -> list[str]:
    """damping_acceleration(v) = -M⁻¹C v: through C for modal damping, else per mass or by dashpot list."""
    model = c.model
    if not model.damped:
        return []
    if model.modal_zeta is not None:
        return matrix_damping_acceleration_lines(c.kw, c.kwcall)
    what = " and ".join((["the dampers"] if model.dampers else [])
                        + (["Rayleigh damping"] if model.rayleigh is not None else []))
    if c.dense or model.rayleigh is not None:  # Rayleigh terms are per mass: one line each, no N x N
        from .rayleigh_targets import binding_lines, private

        damp = [private(e) for e in model.force_expressions(Effect.DAMPER, Effect.RAYLEIGH)]
        body = [*binding_lines(model, c.kwcall),  # _alpha_R, _beta_R of [damping] rayleigh_targets
                f"    {c.unpack(model.v)} = _v", "    _out = numpy.empty(numpy.shape(_v))",
                *c.per_mass(damp), "    return _out"]
    else:
        body = _incidence_lines(c, "_v", "_DAMPER_ENDS", "damper_constants", cubic=False)
        body.append(f"    return _f / masses({c.kwcall}).reshape(_col)")
    return function(f"damping_acceleration(_v{c.kw})",
                    f"Acceleration -M^-1 C v from {what}; v and result have shape (N, ...).", body)


def _external_acceleration(c: _Context) -> list[str]:
    """external_acceleration(t) = M⁻¹F(t) of the ``[[forces]]`` expressions."""
    model = c.model
    if not model.forces:
        return []
    ext = model.force_expressions(Effect.FORCE)
    body = ["    t = numpy.asarray(t, dtype=float)", "    _out = numpy.zeros((_N,) + t.shape)"]
    body += c.per_mass(ext, skip_zero=True)
    return function(f"external_acceleration(t{c.kw})",
                    "Acceleration M^-1 F(t) from the external forces; t scalar or array, result (N, *t.shape).",
                    body + ["    return _out"])


def _gravity(c: _Context) -> list[str]:
    """gravity_forces(): the constant m_i g of ``[gravity]``."""
    if c.model.g is None:
        return []
    return function(f"gravity_forces({c.sig})", "Constant gravity force m_i*g on each mass (+x direction), shape (N,).",
                    [f"    return {array([c.p(f) for f in c.model.gravity_force])}"])


_HARMONICS_DOC = """External forces as F(t) = const + sum_h cos_amp[h] cos(omega[h] t) + sin_amp[h] sin(omega[h] t).

Returns
-------
omega : ndarray, shape (H,)
cos_amp, sin_amp : ndarray, shape (H, N)
const : ndarray, shape (N,)
"""


def _forcing_harmonics(c: _Context) -> list[str]:
    """FORCING_HARMONIC and, when the forces are constant + harmonic, forcing_harmonics()."""
    model = c.model
    if not model.forces:
        return []
    harmonic = harmonic_table([(on, f) for on, f, _ in model.forces], model.t, model.scene.n)
    out = ["", f"FORCING_HARMONIC = {harmonic is not None!r}"]
    if harmonic is None:
        return out
    const, freqs, cos_amp, sin_amp = harmonic

    def rows(table) -> str:
        return "numpy.array([" + ", ".join(array([c.p(e) for e in row]) for row in table) + "]).reshape(_omega.shape[0], _N)"

    return out + function(f"forcing_harmonics({c.sig})", _HARMONICS_DOC,
                          [f"    _omega = {array([c.p(f) for f in freqs])}",
                           f"    _cos = {rows(cos_amp)}",
                           f"    _sin = {rows(sin_amp)}",
                           f"    _const = {array([c.p(e) for e in const])}",
                           "    return _omega, _cos, _sin, _const"])


def _tables_and_ground(c: _Context) -> list[str]:
    """Tabulated forces and ground motion (:mod:`derive.loadgen`, shared with chain modules)."""
    model = c.model
    ons = [on for on, _, _ in model.table_forces]
    out = table_force_lines(ons, [model.masses[on] for on in ons], c.sig, chain=False)
    if model.scene.ground is not None:
        out += ground_lines(model.ground, model.ground_motion, model.t, c.sig)
    return out


def _energy(c: _Context) -> list[str]:
    """energy(x, v) = T + V (gravity's potential included): one expression, or sums over element lists."""
    model = c.model
    doc = "Total energy T + V" + (" (V includes gravity's potential)" if model.g is not None else "") + \
        (" (each spring potential counted from its value at rest, V(d) - V(0))" if c.laws else "") + \
        "; x, v shape (N, ...), result shape (...)."
    if c.laws:
        return function(f"energy(_x, _v{c.kw})", doc, dense_energy_lines(model, c.kwcall))
    if c.dense:
        body = [f"    {c.unpack(model.x)} = _x", f"    {c.unpack(model.v)} = _v", f"    return {c.p(model.energy)}"]
        return function(f"energy(_x, _v{c.kw})", doc, body)
    body = _incidence_lines(c, "_x", "_SPRING_ENDS", "spring_constants", cubic=True, forces=False)
    body += ["    _v = numpy.asarray(_v, dtype=_float)",
             f"    _e = 0.5 * numpy.sum(masses({c.kwcall}).reshape(_col) * _v**2, axis=0)",
             f"    _e = _e + 0.5 * numpy.sum(spring_constants({c.kwcall}).reshape(_col) * _d**2, axis=0)"]
    if c.cubic:
        body.append(f"    _e = _e + 0.25 * numpy.sum(cubic_constants({c.kwcall}).reshape(_col) * _d**4, axis=0)")
    if model.g is not None:
        body.append(f"    _e = _e - numpy.sum(gravity_forces({c.kwcall}).reshape(_col) * _x, axis=0)")
    return function(f"energy(_x, _v{c.kw})", doc, body + ["    return _e"])


def _spring_laws(c: _Context) -> list[str]:
    """Spring potentials: spring_tensions(), spring_stiffnesses(), the energies, equilibrium() and the
    series helpers they call (:mod:`derive.potential_code`)."""
    return dense_law_lines(c.model, c.sig, c.kwcall) if c.laws else []


#: The section writers of a ``[masses]`` module, in the order they appear in it.
SECTIONS = (_constants, _element_constants, _mass_and_stiffness, _damping_matrix, _dynamical_matrix,
            _spectrum, _spectrum_helper, _acceleration, _scalar_force, _bound_acceleration, _damping_acceleration,
            _external_acceleration, _gravity, _forcing_harmonics, _tables_and_ground, _energy, _spring_laws,
            band_section)


def render_module(model: Model, modes: ModeSet, *, bundled: bool = True) -> str:
    """The generated module's source for a ``[masses]``/``[[springs]]`` scene.

    Parameters
    ----------
    model : Model
        The derived model.
    modes : ModeSet
        Its closed-form (or numeric fallback) modes.
    bundled : bool
        Whether the scene is one of ``scenes/`` (affects only the regenerate line).

    Returns
    -------
    str
        Python source; byte-identical for the same scene.
    """
    c = _Context(model, modes)
    head = module_head(model.scene, c.params, _doc(model), scipy=c.accurate_helper, bundled=bundled)
    return render(head, SECTIONS, c)


__all__ = ["MAX_PRINTED_MATRIX", "SECTIONS", "render_module"]
