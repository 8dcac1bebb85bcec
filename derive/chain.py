"""Long chains (``[chain]`` scenes): derive one element, generate a stencil.

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

from .printing import sstr
from ..ends import End
from .codegen import _p, header, privatize, regenerate_command
from .model import parameter_symbols
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
        self.k = self.chain.k.to_sympy(sym)
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
                             *(["force"] if self.forces else []), *(["table"] if self.table_forces else []),
                             *(["ground"] if self.scene.ground is not None else []),
                             *(["gravity"] if self.g is not None else []),
                             *(["damper"] if self.dampers else []),
                             *(["rayleigh"] if self.rayleigh is not None else [])}))

    @property
    def rigid_modes(self) -> int:
        return 1 if (self.chain.left is not End.WALL and self.chain.right is not End.WALL) else 0


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


def chain_mode_records(model: ChainModel, modes: ChainModes, omega2_values=None) -> tuple[list[dict], str]:
    """Mode records in the schema of non-chain scenes (``omega2``, ``omega2_value``,
    ``multiplicity``, ``shape``), ascending; for long chains only both ends of the spectrum.

    ``omega2_values`` are the n values of the generated module's ``omega2()`` (needed for a
    non-uniform chain; a uniform one evaluates its closed form). ``shape`` is the closed-form
    shape as a function of the mass index ``i`` (None without a closed form); ``shape_value``
    lists its values only for chains of at most MAX_MODES_LISTED masses.
    """
    import numpy as np

    n = model.chain.n
    values = None if omega2_values is None else np.asarray(omega2_values, dtype=float)
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
    if values is None:
        return [], "modes not listed (the eigen-problem is too large to solve densely here)"
    values = np.maximum(np.sort(values), 0.0)
    if n <= MAX_MODES_LISTED:
        picked, note = list(range(n)), ""
    else:
        e = MODES_LISTED_EACH_END
        picked = list(range(e)) + list(range(n - e, n))
        note = (f"modes lists the {e} lowest and {e} highest of the {n} modes; "
                + ("the family omega2(j), shape(i, j) gives every one" if modes.omega2 is not None
                   else "the generated module's omega2() gives every one"))
    scale = float(np.max(np.abs(values))) if values.size else 0.0
    records = []
    for p in picked:
        mult = int(np.count_nonzero(np.abs(values - values[p]) <= 1e-12 * max(scale, 1e-300)))
        rec = {"omega2": sp.sstr(sp.Float(values[p], 17)), "omega2_value": float(values[p]),
               "multiplicity": mult, "shape": None}
        if order is not None:
            j = int(order[p]) + modes.j_range[0]
            rec["j"] = j
            rec["omega2"] = sp.sstr(modes.omega2.subs({model.j: j, model.n: n}))
            shape = modes.shape.subs({model.j: j, model.n: n})
            rec["shape"] = sp.sstr(shape)
            if n <= MAX_MODES_LISTED:
                f = sp.lambdify(model.i, shape, "numpy")
                idx = np.arange(n, dtype=float)
                rec["shape_value"] = [float(v) for v in np.broadcast_to(np.asarray(f(idx), dtype=float), (n,))]
        records.append(rec)
    return records, note


def chain_report(model: ChainModel, modes: ChainModes, omega2_values=None) -> tuple[str, dict]:
    """Text and JSON description of a chain's derivation and spectrum.

    The JSON has the top-level shape of non-chain scenes (``scene, parameters, masses, modes,
    closed_form, notes``; ``masses`` is empty: chain masses are indices 0 … n−1) plus the
    chain's ``n, left, right, uniform, j_range`` and its symbolic ``family`` (omega2, shape).
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
    lines += [f"    note: {note}" for note in modes.notes]
    if model.k3 is not None:
        lines.append("    note: cubic springs: modes of the linearization; no exact solution")
    notes = list(modes.notes) + (["cubic springs: modes of the linearization; no exact solution"]
                                 if model.k3 is not None else [])
    records, listed_note = chain_mode_records(model, modes, omega2_values)
    if records:  # the numbers, for every chain (a closed form or not): as --json lists them
        how = "closed form at the scene's values" if modes.omega2 is not None else \
            "numeric, the generated module's omega2()"
        lines += ["", f"Normal modes ({how}), ascending:"]
        lines += [f"    {'j = ' + str(r['j']) + ':  ' if 'j' in r else ''}ω² = {r['omega2_value']:.10g}"
                  + (f"  (multiplicity {r['multiplicity']})" if r["multiplicity"] > 1 else "") for r in records]
        if listed_note:
            lines.append(f"    note: {listed_note}")
    elif listed_note:
        lines.append(f"    note: {listed_note}")
    data = {"scene": sc.name, "parameters": {k: sc.parameters[k] for k in sorted(sc.parameters)},
            "masses": [], "modes": records, "closed_form": modes.closed_form,
            "notes": notes + ([listed_note] if listed_note else []),
            "n": ch.n, "left": ch.left, "right": ch.right, "uniform": ch.uniform,
            "j_range": None if modes.j_range is None else list(modes.j_range),
            "family": {"omega2": None if modes.omega2 is None else sp.sstr(modes.omega2),
                       "shape": None if modes.shape is None else sp.sstr(modes.shape)}}
    if damping_data is not None:
        data["damping"] = damping_data
    return "\n".join(lines) + "\n", data


def _index_expr(expr: sp.Expr, model: ChainModel, at: str) -> str:
    """Print an expression of i with i replaced by the NumPy name ``at``."""
    return _p(expr.subs(model.i, sp.Symbol(at)))


def render_chain_module(model: ChainModel, *, bundled: bool = True) -> str:
    """Stencil module for a chain; its size does not depend on n."""
    sc, ch = model.scene, model.chain
    params = list(model.params)
    sig = ", ".join(params)
    kw = ", ".join(f"{p}={p}" for p in params)
    w_lines: list[str] = []
    w = w_lines.append
    w(header(sc.name, sc.sha256, regenerate_command(sc.file, bundled)).rstrip("\n"))
    w(f'"""Stencil equations of motion of the chain scene {sc.name!r} (n = {ch.n}).')
    w("")
    w("Coordinates are displacements of masses 0 … n−1 from the springs' rest configuration;")
    w("arrays of states have shape (n, ...). Every function takes the parameters PARAMETERS as")
    w("keyword arguments and works for any n (default N). Nothing here is n×n except")
    w("stiffness_matrix()/mass_matrix(), which refuse large n.")
    w('"""')
    w("")
    w("import numpy as _np")
    w("import scipy.linalg as _linalg")
    w("")
    w(f"SCENE = {sc.name!r}")
    w(f"SCENE_SHA256 = {sc.sha256!r}")
    w(f"PARAMETERS = {tuple(params)!r}")
    w(f"DEFAULTS = {{{', '.join(f'{p!r}: {sc.parameters[p]!r}' for p in params)}}}")
    w(f"N = {ch.n}")
    w("CHAIN = True")
    w(f"LEFT = {ch.left.value!r}")
    w(f"RIGHT = {ch.right.value!r}")
    w(f"UNIFORM = {ch.uniform!r}")
    w(f"EFFECTS = {model.effects!r}")
    w(f"LINEAR = {model.k3 is None!r}")
    w(f"RIGID_MODES = {model.rigid_modes}")
    w("MAX_DENSE = 4000")
    w("")
    w("")
    w(f"def masses({sig}, n=N):")
    w('    """Masses m(i), shape (n,)."""')
    w("    i = numpy.arange(n, dtype=float)")
    w(f"    return numpy.broadcast_to(numpy.asarray({_index_expr(model.mass, model, 'i')}, dtype=float), (n,)).copy()")
    w("")
    w("")
    w(f"def _spring_k(i{', ' + sig if sig else ''}):")
    w('    """Stiffness k(i) of the spring between masses i and i+1 (i = -1: left wall)."""')
    w(f"    return numpy.asarray({_index_expr(model.k, model, 'i')}, dtype=float)")
    if model.k3 is not None:
        w("")
        w("")
        w(f"def _spring_k3(i{', ' + sig if sig else ''}):")
        w('    """Cubic coefficient k3(i) of spring i."""')
        w(f"    return numpy.asarray({_index_expr(model.k3, model, 'i')}, dtype=float)")
    w("")
    w("")
    w("def spring_ends(n=N):")
    w('    """Spring ends (mass indices, -1 = wall) in spring_constants() order, shape (S, 2)."""')
    w("    i = numpy.arange(n - 1)")
    w("    _parts = [numpy.stack([i, i + 1], axis=1)]")
    if ch.left is End.WALL:
        w("    _parts.insert(0, numpy.array([[-1, 0]]))")
    if ch.right is End.WALL:
        w("    _parts.append(numpy.array([[n - 1, -1]]))")
    if ch.left is End.RING:
        w("    _parts.append(numpy.array([[n - 1, 0]]))")
    w("    return numpy.concatenate(_parts).astype(numpy.intp)")
    w("")
    w("")
    w(f"def spring_constants({sig}, n=N):")
    w('    """Stiffness of each spring in spring_ends() order, shape (S,)."""')
    w("    i = numpy.arange(n - 1, dtype=float)")
    w(f"    _parts = [numpy.broadcast_to(_spring_k(i, {kw}), (n - 1,))]")
    if ch.left is End.WALL:
        w(f"    _parts.insert(0, numpy.broadcast_to(_spring_k(numpy.array([-1.0]), {kw}), (1,)))")
    if ch.right.has_spring:
        w(f"    _parts.append(numpy.broadcast_to(_spring_k(numpy.array([n - 1.0]), {kw}), (1,)))")
    w("    return numpy.concatenate(_parts).astype(float)")
    if model.k3 is not None:
        w("")
        w("")
        w(f"def spring_cubic_constants({sig}, n=N):")
        w('    """Cubic coefficient k3 of each spring in spring_ends() order, shape (S,)."""')
        w("    i = numpy.arange(n - 1, dtype=float)")
        w(f"    _parts = [numpy.broadcast_to(_spring_k3(i, {kw}), (n - 1,))]")
        if ch.left is End.WALL:
            w(f"    _parts.insert(0, numpy.broadcast_to(_spring_k3(numpy.array([-1.0]), {kw}), (1,)))")
        if ch.right.has_spring:
            w(f"    _parts.append(numpy.broadcast_to(_spring_k3(numpy.array([n - 1.0]), {kw}), (1,)))")
        w("    return numpy.concatenate(_parts).astype(float)")
    w("")
    w("")
    cubic = model.k3 is not None
    w(f"def make_acceleration({sig}, n=N):")
    w('    """A function a(x) for this chain with coefficients precomputed; x shape (n, ...).')
    w("")
    w("    The stencil: the spring between i and i+1 pulls with s_i = k_i d_i [+ k3_i d_i³],")
    w('    d_i = x_{i+1} − x_i; mass i feels s_i − s_{i−1}; walls and the ring closure act at the ends."""')
    w("    i = numpy.arange(n - 1, dtype=float)")
    w(f"    _inv_m = 1.0 / masses({kw}, n=n)")
    if model.g is not None:  # m_i g / m_i: the same acceleration on every mass
        w(f"    _g_acc = _float({_p(model.g)})")
    if ch.uniform:
        w("    _inv_m = _float(_inv_m[0])")
        w(f"    _ks = _float(_spring_k(0.0, {kw}))")
        if cubic:
            w(f"    _k3s = _float(_spring_k3(0.0, {kw}))")
    else:
        w(f"    _ks1 = numpy.broadcast_to(_spring_k(i, {kw}), (n - 1,))")
        if cubic:
            w(f"    _k3s1 = numpy.broadcast_to(_spring_k3(i, {kw}), (n - 1,))")
        w("    _inv_m1 = _inv_m")
    if ch.left is End.WALL:
        w(f"    _k_left = _float(_spring_k(numpy.array(-1.0), {kw}))")
        if cubic:
            w(f"    _k3_left = _float(_spring_k3(numpy.array(-1.0), {kw}))")
    if ch.right.has_spring:
        w(f"    _k_right = _float(_spring_k(numpy.array(n - 1.0), {kw}))")
        if cubic:
            w(f"    _k3_right = _float(_spring_k3(numpy.array(n - 1.0), {kw}))")
    w("")
    w("    def _stencil(_y):")
    if not ch.uniform:  # per-mass coefficients broadcast against (n,) or (n, ...)
        w("        _shape = (-1,) + (1,) * (numpy.ndim(_y) - 1)")
        w("        _ks, _inv_m = _ks1.reshape(_shape), _inv_m1.reshape(_shape)")
        if cubic:
            w("        _k3s = _k3s1.reshape(_shape)")
    w("        _f = numpy.empty(numpy.shape(_y))")
    w("        _d = _y[1:] - _y[:-1]")
    w("        _s = _ks * _d" + (" + _k3s * _d**3" if cubic else ""))
    w("        _f[:-1] = _s")
    w("        _f[-1] = 0.0")
    w("        _f[1:] -= _s")
    if ch.left is End.WALL:
        w("        _f[0] -= _k_left * _y[0]" + (" + _k3_left * _y[0]**3" if cubic else ""))
    if ch.right is End.WALL:
        w("        _f[-1] -= _k_right * _y[-1]" + (" + _k3_right * _y[-1]**3" if cubic else ""))
    if ch.left is End.RING:
        w("        _dr = _y[0] - _y[-1]")
        w("        _sr = _k_right * _dr" + (" + _k3_right * _dr**3" if cubic else ""))
        w("        _f[-1] += _sr")
        w("        _f[0] -= _sr")
    w("        _f *= _inv_m")
    if model.g is not None:
        w("        _f += _g_acc")
    w("        return _f")
    w("")
    w("    return _stencil")
    w("")
    w("")
    w(f"def acceleration(_x, {sig}):")
    w('    """Acceleration of the chain; x shape (n, ...) (n taken from x)."""')
    w(f"    return make_acceleration({kw}, n=numpy.shape(_x)[0])(_x)")
    w("")
    w("")
    w(f"def energy(_x, _v, {sig}):")
    w('    """Total energy; x, v shape (n, ...) -> (...)."""')
    w("    n = numpy.shape(_x)[0]")
    w("    _extra = (1,) * (numpy.ndim(_x) - 1)")
    w(f"    _m = masses({kw}, n=n).reshape((n,) + _extra)")
    w(f"    _kk = spring_constants({kw}, n=n)")
    w("    _ends = spring_ends(n)")
    w("    _xa = numpy.where((_ends[:, 0] >= 0).reshape((-1,) + _extra), _x[_ends[:, 0]], 0.0)")
    w("    _xb = numpy.where((_ends[:, 1] >= 0).reshape((-1,) + _extra), _x[_ends[:, 1]], 0.0)")
    w("    _d = _xb - _xa")
    w("    _e = 0.5 * numpy.sum(_m * _v**2, axis=0) + 0.5 * numpy.sum(_kk.reshape((-1,) + _extra) * _d**2, axis=0)")
    if cubic:
        w(f"    i = numpy.arange(_kk.shape[0], dtype=float) - (1.0 if _LEFT == {End.WALL.value!r} else 0.0)")
        w(f"    _k3s = numpy.broadcast_to(_spring_k3(i, {kw}), _kk.shape)")
        w("    _e = _e + 0.25 * numpy.sum(_k3s.reshape((-1,) + _extra) * _d**4, axis=0)")
    if model.g is not None:
        w(f"    _e = _e - ({_p(model.g)}) * numpy.sum(_m * _x, axis=0)")
    w("    return _e")
    from .loadgen import chain_load_code

    w_lines.extend(chain_load_code(model, sig, kw))
    from .chain_damping_code import chain_damping_code

    w_lines.extend(chain_damping_code(model, sig, kw))
    w("")
    w("")
    w(f"def stiffness_bands({sig}, n=N):")
    w('    """Diagonal (n,) and first off-diagonal (n-1,) of K (ring closure not included)."""')
    w(f"    _kk = spring_constants({kw}, n=n)")
    w("    _ends = spring_ends(n)")
    w("    _diag = numpy.zeros(n)")
    w("    for _col in (0, 1):")
    w("        _idx = _ends[:, _col]")
    w("        numpy.add.at(_diag, _idx[_idx >= 0], _kk[_idx >= 0])")
    w("    _inner = (_ends[:, 0] >= 0) & (_ends[:, 1] >= 0) & (numpy.abs(_ends[:, 0] - _ends[:, 1]) == 1)")
    w("    _off = numpy.zeros(n - 1)")
    w("    _off[numpy.minimum(_ends[_inner, 0], _ends[_inner, 1])] = -_kk[_inner]")
    w("    return _diag, _off")
    w("")
    w("")
    w(f"def stiffness_matrix({sig}, n=N):")
    w('    """Dense K, shape (n, n); only for n <= MAX_DENSE."""')
    w("    if n > _MAX_DENSE:")
    w("        raise ValueError(f'stiffness_matrix: n = {n} > MAX_DENSE = {_MAX_DENSE}; use stiffness_bands()')")
    w(f"    _diag, _off = stiffness_bands({kw}, n=n)")
    w("    _K = numpy.diag(_diag) + numpy.diag(_off, 1) + numpy.diag(_off, -1)")
    if ch.left is End.RING:
        w(f"    _kr = spring_constants({kw}, n=n)[-1]")
        w("    _K[0, n - 1] -= _kr")
        w("    _K[n - 1, 0] -= _kr")
    w("    return _K")
    w("")
    w("")
    w(f"def mass_matrix({sig}, n=N):")
    w('    """Dense M, shape (n, n); only for n <= MAX_DENSE."""')
    w("    if n > _MAX_DENSE:")
    w("        raise ValueError(f'mass_matrix: n = {n} > MAX_DENSE = {_MAX_DENSE}')")
    w(f"    return numpy.diag(masses({kw}, n=n))")
    w("")
    w("")
    modes = chain_modes(model)
    w(f"def omega2({sig}, n=N):")
    if modes.omega2 is not None:
        lo, _ = modes.j_range
        w('    """Closed-form squared angular frequencies, ascending, shape (n,)."""')
        w(f"    _j = numpy.arange({lo}, n + {lo}, dtype=float)")
        expr = modes.omega2.subs({model.j: sp.Symbol("_j"), model.n: sp.Symbol("n")})
        w(f"    return numpy.sort(numpy.broadcast_to({_p(expr)}, (n,)))")
        w("")
        w("")
        w(f"def mode_omega({sig}, n=N):")
        w(f'    """Closed-form angular frequencies of modes j = {lo} … n{lo - 1:+d} in index order (not sorted), shape (n,).')
        w("")
        w("    The order of the chain's sine/cosine/Fourier transform: the numeric exact solution of long")
        w('    uniform chains takes its frequencies from here."""')
        w(f"    _j = numpy.arange({lo}, n + {lo}, dtype=float)")
        w(f"    return numpy.sqrt(numpy.broadcast_to({_p(expr)}, (n,)))")
    elif ch.left is End.RING:
        import textwrap

        from .spring_factor import helper_source

        w('    """Squared angular frequencies (index-dependent ring), ascending, shape (n,).')
        w("")
        w("    The spring-factor route (subtraction-free LDLᵀ of K, one-sided Jacobi SVD of its factor), as")
        w("    the dense modules run it: accurate to float64 in the relative sense at any positive masses")
        w('    and springs; the rigid mode exactly 0. Cost O(n³)."""')
        w(f"    return _ring_omega2(masses({kw}, n=n), spring_constants({kw}, n=n), spring_ends(n=n), n)")
        w("")
        w("")
        w("def _ring_omega2(_m, _k, _ends, n):")
        w('    """ω² of a ring of n masses by the spring-factor helper below (its globals bound here)."""')
        w("    N, SPRING_ENDS, RIGID_PIECES = n, _ends, (tuple(range(n)),)")
        w(textwrap.indent(helper_source().rstrip("\n"), "    "))
        w("")
        w("    return _accurate_modes(_m, _k)[0]")
    else:
        _bidiagonal_omega2(w, ch, kw)
    return privatize("\n".join(w_lines) + "\n")


def _bidiagonal_omega2(w, ch, kw: str) -> None:
    """The body of omega2() for an index-dependent open chain (no closed form).

    D = M^-1/2 K M^-1/2 = GᵀG with G = diag(√k) B M^-1/2 (B the spring incidence), and G of an
    open chain is bidiagonal (square after appending a zero row, whose zero singular value is
    dropped, or is the rigid mode). ω are G's singular values, found by bisection on the
    Golub–Kahan form (zero diagonal, off-diagonals interleaving G's entries; LAPACK stebz with
    a tolerance below the underflow threshold), which is accurate in the relative sense for any
    positive masses and springs (Demmel & Kahan 1990; LAPACK's dbdsvdx does the same). Forming
    D and calling eigh_tridiagonal is not: its small ω² lose ~κ(D)·ε.
    """
    w('    """Squared angular frequencies (no closed form), ascending, shape (n,).')
    w("")
    w("    Singular values of the bidiagonal spring factor G (GᵀG = M^-1/2 K M^-1/2) by bisection on its")
    w("    Golub–Kahan form: accurate to float64 in the relative sense at any positive masses and springs;")
    w("    rigid modes exactly 0. Cost O(n²).\"\"\"")
    w(f"    _rm = 1.0 / numpy.sqrt(masses({kw}, n=n))")
    w(f"    _rk = numpy.sqrt(spring_constants({kw}, n=n))")
    if ch.left is End.WALL:  # rows: the wall spring (mass 0), then spring r between r-1 and r
        w("    _a = _rk[:n] * _rm")
        w("    _b = _rk[1:n] * _rm[:n - 1]")
        if ch.right is End.WALL:
            w("    _a, _b = numpy.append(_a, 0.0), numpy.append(_b, _rk[n] * _rm[n - 1])")
    else:  # rows: spring r between r and r+1, then the right wall's spring or a zero row
        w("    _a = _rk[:n - 1] * _rm[:n - 1]")
        w("    _b = _rk[:n - 1] * _rm[1:]")
        w("    _a = numpy.append(_a, " + ("_rk[n - 1] * _rm[n - 1]" if ch.right is End.WALL else "0.0") + ")")
    w("    _s = _a.shape[0]")
    w("    _t = numpy.empty(2 * _s - 1)")
    w("    _t[0::2], _t[1::2] = _a, _b")
    w("    _sv = scipy.linalg.eigh_tridiagonal(numpy.zeros(2 * _s), _t, eigvals_only=True, select='i',")
    w("                                        select_range=(_s, 2 * _s - 1), lapack_driver='stebz',")
    w("                                        tol=numpy.finfo(numpy.float64).tiny)")
    w("    _w = numpy.sort(numpy.abs(_sv))[_s - n:] ** 2")
    w("    _w[:_RIGID_MODES] = 0.0")
    w("    return _w")
