"""Render a ``[chain]`` scene as a stencil module whose size does not depend on n.

The module is :func:`derive.module_text.module_head` (the header every generated module shares)
followed by the section writers in :data:`SECTIONS`, one per concern: constants, masses, spring
coefficients and lists, the stencil acceleration, energy, loads, damping, the banded and dense
matrices, the spectrum. Each is a function ``(context) -> list[str]`` of a :class:`_Context`.
The element template and the closed-form spectrum come from :mod:`derive.chain`; nothing here
is symbolic work beyond printing.

Adding an effect to chains touches this file in one place: a section writer that returns its
functions' lines (:func:`derive.module_text.function`) placed in :data:`SECTIONS`; writers shared
with ``[masses]`` modules (:mod:`derive.loadgen`) or long enough for a module of their own
(:mod:`derive.chain_damping_code`) are listed the same way.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from ..generated.contract import MAX_DENSE, End
from .chain import ChainModel, ChainModes, chain_modes
from .chain_damping_code import chain_damping_code
from .codeprint import p
from .loadgen import chain_load_code
from .module_text import function, module_head, render
from .potential_code import chain_law_lines, chain_tension_code
from .spring_factor import helper_source
from .bands.codegen import band_section


@dataclass(frozen=True)
class _Context:
    """What every section writer of a chain module reads (built once per render)."""

    model: ChainModel
    modes: ChainModes

    @cached_property
    def params(self) -> tuple[str, ...]:
        return tuple(self.model.params)

    @cached_property
    def sig(self) -> str:
        """The parameters as a signature: ``k, m``."""
        return ", ".join(self.params)

    @cached_property
    def kw(self) -> str:
        """The parameters passed on: ``k=k, m=m``."""
        return ", ".join(f"{q}={q}" for q in self.params)

    def sig_and(self, *more: str) -> str:
        """The signature followed by more parameters: ``k, m, n=N`` (``n=N`` without parameters)."""
        return ", ".join([*self.params, *more])

    def kw_and(self, *more: str) -> str:
        """The parameters passed on, then more arguments: ``k=k, m=m, n=n``."""
        return ", ".join([*(f"{q}={q}" for q in self.params), *more])

    @property
    def chain(self):
        return self.model.chain

    @property
    def cubic(self) -> bool:
        return self.model.k3 is not None

    def of_i(self, expr: sp.Expr, at: str = "i") -> str:
        """Print an expression of the index i with i replaced by the NumPy name ``at``."""
        return p(expr.subs(self.model.i, sp.Symbol(at)))


def _doc(c: _Context) -> str:
    return (f"Stencil equations of motion of the chain scene {c.model.scene.name!r} (n = {c.chain.n}).\n\n"
            "Coordinates are displacements of masses 0 … n−1 from the springs' rest configuration;\n"
            "arrays of states have shape (n, ...). Every function takes the parameters PARAMETERS as\n"
            "keyword arguments and works for any n (default N). Nothing here is n×n except\n"
            "stiffness_matrix()/mass_matrix(), which refuse large n.\n")


# -- sections ----------------------------------------------------------------------------------
def _constants(c: _Context) -> list[str]:
    """The chain's shape: length, ends, uniformity, effects, rigid modes, the dense limit."""
    ch, model = c.chain, c.model
    return [f"N = {ch.n}", "CHAIN = True", f"LEFT = {ch.left.value!r}", f"RIGHT = {ch.right.value!r}",
            f"UNIFORM = {ch.uniform!r}", f"EFFECTS = {model.effects!r}", f"LINEAR = {model.linear!r}",
            f"RIGID_MODES = {model.rigid_modes}", f"MAX_DENSE = {MAX_DENSE}"]


def _masses(c: _Context) -> list[str]:
    """masses(n): m(i) for i = 0 … n−1."""
    return function(f"masses({c.sig_and('n=N')})", "Masses m(i), shape (n,).",
                    ["    i = numpy.arange(n, dtype=float)",
                     f"    return numpy.broadcast_to(numpy.asarray({c.of_i(c.model.mass)}, dtype=float), (n,)).copy()"])


def _spring_coefficients(c: _Context) -> list[str]:
    """_spring_k(i) and, for cubic springs, _spring_k3(i): the coefficients as functions of i."""
    after = ", " + c.sig if c.sig else ""
    out = function(f"_spring_k(i{after})", "Stiffness k(i) of the spring between masses i and i+1 (i = -1: left wall).",
                   [f"    return numpy.asarray({c.of_i(c.model.k)}, dtype=float)"])
    if c.cubic:
        out += function(f"_spring_k3(i{after})", "Cubic coefficient k3(i) of spring i.",
                        [f"    return numpy.asarray({c.of_i(c.model.k3)}, dtype=float)"])
    return out


def _spring_lists(c: _Context) -> list[str]:
    """spring_ends(n), spring_constants(n) and, for cubic springs, spring_cubic_constants(n)."""
    ch = c.chain
    ends = ["    i = numpy.arange(n - 1)", "    _parts = [numpy.stack([i, i + 1], axis=1)]"]
    ends += ["    _parts.insert(0, numpy.array([[-1, 0]]))"] if ch.left is End.WALL else []
    ends += ["    _parts.append(numpy.array([[n - 1, -1]]))"] if ch.right is End.WALL else []
    ends += ["    _parts.append(numpy.array([[n - 1, 0]]))"] if ch.left is End.RING else []
    out = function("spring_ends(n=N)", "Spring ends (mass indices, -1 = wall) in spring_constants() order, shape (S, 2).",
                   ends + ["    return numpy.concatenate(_parts).astype(numpy.intp)"])
    out += _per_spring(c, "spring_constants", "_spring_k", "Stiffness")
    if c.cubic:
        out += _per_spring(c, "spring_cubic_constants", "_spring_k3", "Cubic coefficient k3")
    return out


def _per_spring(c: _Context, name: str, coefficient: str, what: str) -> list[str]:
    """A per-spring array in spring_ends() order from the coefficient function ``coefficient(i)``."""
    body = ["    i = numpy.arange(n - 1, dtype=float)", f"    _parts = [numpy.broadcast_to({coefficient}(i, {c.kw}), (n - 1,))]"]
    if c.chain.left is End.WALL:
        body.append(f"    _parts.insert(0, numpy.broadcast_to({coefficient}(numpy.array([-1.0]), {c.kw}), (1,)))")
    if c.chain.right.has_spring:
        body.append(f"    _parts.append(numpy.broadcast_to({coefficient}(numpy.array([n - 1.0]), {c.kw}), (1,)))")
    return function(f"{name}({c.sig_and('n=N')})", f"{what} of each spring in spring_ends() order, shape (S,).",
                    body + ["    return numpy.concatenate(_parts).astype(float)"])


def _stencil(c: _Context) -> list[str]:
    """make_acceleration(n): coefficients formed once, then an O(n) stencil closure."""
    return function(f"make_acceleration({c.sig_and('n=N')})",
                    "A function a(x) for this chain with coefficients precomputed; x shape (n, ...).\n\n"
                    "The stencil: the spring between i and i+1 pulls with s_i = k_i d_i [+ k3_i d_i³],\n"
                    "d_i = x_{i+1} − x_i; mass i feels s_i − s_{i−1}; walls and the ring closure act at the ends.",
                    _stencil_coefficients(c) + ["", "    def _stencil(_y):", *_stencil_body(c), "", "    return _stencil"])


def _stencil_coefficients(c: _Context) -> list[str]:
    """make_acceleration()'s set-up: 1/m, the spring coefficients (scalars for a uniform chain), ends."""
    ch, kw, cubic = c.chain, c.kw, c.cubic
    out = ["    i = numpy.arange(n - 1, dtype=float)", f"    _inv_m = 1.0 / masses({c.kw_and('n=n')})"]
    if c.model.g is not None:  # m_i g / m_i: the same acceleration on every mass
        out.append(f"    _g_acc = _float({p(c.model.g)})")
    if ch.uniform:
        out += ["    _inv_m = _float(_inv_m[0])", f"    _ks = _float(_spring_k(0.0, {kw}))"]
        out += [f"    _k3s = _float(_spring_k3(0.0, {kw}))"] if cubic else []
    else:
        out.append(f"    _ks1 = numpy.broadcast_to(_spring_k(i, {kw}), (n - 1,))")
        out += [f"    _k3s1 = numpy.broadcast_to(_spring_k3(i, {kw}), (n - 1,))"] if cubic else []
        out.append("    _inv_m1 = _inv_m")
    for end, at, present in (("left", "-1.0", ch.left is End.WALL), ("right", "n - 1.0", ch.right.has_spring)):
        if present:
            out.append(f"    _k_{end} = _float(_spring_k(numpy.array({at}), {kw}))")
            out += [f"    _k3_{end} = _float(_spring_k3(numpy.array({at}), {kw}))"] if cubic else []
    return out


def _stencil_body(c: _Context) -> list[str]:
    """The closure's body: element forces s_i, their differences, the ends, 1/m and gravity."""
    ch, cubic = c.chain, c.cubic
    if c.model.law is not None:
        return _law_stencil_body(c)

    def cube(k3: str, d: str) -> str:
        return f" + {k3} * {d}**3" if cubic else ""

    out = []
    if not ch.uniform:  # per-mass coefficients broadcast against (n,) or (n, ...)
        out += ["        _shape = (-1,) + (1,) * (numpy.ndim(_y) - 1)",
                "        _ks, _inv_m = _ks1.reshape(_shape), _inv_m1.reshape(_shape)"]
        out += ["        _k3s = _k3s1.reshape(_shape)"] if cubic else []
    return out + _stencil_lines(c, tension="_ks * _d" + cube("_k3s", "_d"),
                                left="_f[0] -= _k_left * _y[0]" + cube("_k3_left", "_y[0]"),
                                right="_f[-1] -= _k_right * _y[-1]" + cube("_k3_right", "_y[-1]"),
                                ring="_k_right * _dr" + cube("_k3_right", "_dr"), inv_m="_f *= _inv_m")


def _stencil_lines(c: _Context, tension: str, left: str, right: str, ring: str, inv_m: str) -> list[str]:
    """The stencil's statements from its spring terms: ``tension`` of the links (of ``_d``), the wall
    statements ``left`` and ``right``, the ring's closing tension ``ring`` (of ``_dr``), the 1/m
    statement ``inv_m``; then gravity and the return."""
    ch = c.chain
    out = ["_f = numpy.empty(numpy.shape(_y))", "_d = _y[1:] - _y[:-1]", "_s = " + tension, "_f[:-1] = _s",
           "_f[-1] = 0.0", "_f[1:] -= _s"]
    out += [left] if ch.left is End.WALL else []
    out += [right] if ch.right is End.WALL else []
    out += ["_dr = _y[0] - _y[-1]", "_sr = " + ring, "_f[-1] += _sr", "_f[0] -= _sr"] if ch.left is End.RING else []
    out += [inv_m] + (["_f += _g_acc"] if c.model.g is not None else []) + ["return _f"]
    return ["        " + line for line in out]


def _law_stencil_body(c: _Context) -> list[str]:
    """The closure's body for a spring potential: tensions from spring_force() (:mod:`derive.potential_code`);
    the wall springs have d = x_0 (left) and d = -x_{n-1} (right), the ring's closing spring x_0 - x_{n-1}."""
    ch = c.chain

    def tension(d: str, index: str) -> str:
        return chain_tension_code(c.model, c.kw, d, index)

    column = "(-1,) + (1,) * (numpy.ndim(_y) - 1)"  # per-mass values broadcast against (n,) or (n, ...)
    return _stencil_lines(c, tension=tension("_d", f"i.reshape({column})"),
                          left="_f[0] -= " + tension("_y[0]", "-1.0"),
                          right="_f[-1] += " + tension("-_y[-1]", "n - 1.0"), ring=tension("_dr", "n - 1.0"),
                          inv_m="_f *= _inv_m" if ch.uniform else f"_f *= _inv_m1.reshape({column})")


def _acceleration(c: _Context) -> list[str]:
    """acceleration(x): the stencil for x's length."""
    return function(f"acceleration(_x, {c.sig})", "Acceleration of the chain; x shape (n, ...) (n taken from x).",
                    [f"    return make_acceleration({c.kw_and('n=numpy.shape(_x)[0]')})(_x)"])


def _energy(c: _Context) -> list[str]:
    """energy(x, v): kinetic plus spring (and cubic, gravity) energy over the spring list."""
    kw = c.kw
    body = ["    n = numpy.shape(_x)[0]",
            "    _extra = (1,) * (numpy.ndim(_x) - 1)",
            f"    _m = masses({c.kw_and('n=n')}).reshape((n,) + _extra)",
            f"    _kk = spring_constants({c.kw_and('n=n')})",
            "    _ends = spring_ends(n)",
            "    _xa = numpy.where((_ends[:, 0] >= 0).reshape((-1,) + _extra), _x[_ends[:, 0]], 0.0)",
            "    _xb = numpy.where((_ends[:, 1] >= 0).reshape((-1,) + _extra), _x[_ends[:, 1]], 0.0)",
            "    _d = _xb - _xa"]
    if c.model.law is not None:  # V(d) - V(0) per spring; the spring index i of each spring_ends() row
        body += [f"    i = (numpy.arange(_kk.shape[0], dtype=float) - (1.0 if _LEFT == {End.WALL.value!r} else 0.0))"
                 ".reshape((-1,) + _extra)",
                 "    _e = 0.5 * numpy.sum(_m * _v**2, axis=0) + numpy.sum("
                 + chain_tension_code(c.model, kw, "_d", "i").replace("spring_force(", "spring_energy(", 1)
                 + ", axis=0)"]
    else:
        body.append("    _e = 0.5 * numpy.sum(_m * _v**2, axis=0) + 0.5 * numpy.sum(_kk.reshape((-1,) + _extra) * _d**2, "
                    "axis=0)")
    if c.cubic:
        body += [f"    i = numpy.arange(_kk.shape[0], dtype=float) - (1.0 if _LEFT == {End.WALL.value!r} else 0.0)",
                 f"    _k3s = numpy.broadcast_to(_spring_k3(i, {kw}), _kk.shape)",
                 "    _e = _e + 0.25 * numpy.sum(_k3s.reshape((-1,) + _extra) * _d**4, axis=0)"]
    if c.model.g is not None:
        body.append(f"    _e = _e - ({p(c.model.g)}) * numpy.sum(_m * _x, axis=0)")
    return function(f"energy(_x, _v, {c.sig})", "Total energy; x, v shape (n, ...) -> (...).", body + ["    return _e"])


def _spring_law(c: _Context) -> list[str]:
    """A spring potential's spring_force(), spring_energy(), spring_stiffness() and equilibrium()
    (:mod:`derive.potential_code`)."""
    return chain_law_lines(c.model, c.sig) if c.model.law is not None else []


def _loads(c: _Context) -> list[str]:
    """Gravity, forces, tables and ground motion (:mod:`derive.loadgen`)."""
    return chain_load_code(c.model, c.sig, c.kw)


def _damping(c: _Context) -> list[str]:
    """The dashpot list, its stencil and dense C (:mod:`derive.chain_damping_code`)."""
    return chain_damping_code(c.model, c.sig, c.kw)


def _matrices(c: _Context) -> list[str]:
    """stiffness_bands(n) and, for n <= MAX_DENSE, the dense stiffness_matrix(n) and mass_matrix(n)."""
    kw = c.kw
    ring = ([f"    _kr = spring_constants({c.kw_and('n=n')})[-1]", "    _K[0, n - 1] -= _kr", "    _K[n - 1, 0] -= _kr"]
            if c.chain.left is End.RING else [])
    return (function(f"stiffness_bands({c.sig_and('n=N')})",
                     "Diagonal (n,) and first off-diagonal (n-1,) of K (ring closure not included).",
                     [f"    _kk = spring_constants({c.kw_and('n=n')})",
                      "    _ends = spring_ends(n)",
                      "    _diag = numpy.zeros(n)",
                      "    for _col in (0, 1):",
                      "        _idx = _ends[:, _col]",
                      "        numpy.add.at(_diag, _idx[_idx >= 0], _kk[_idx >= 0])",
                      "    _inner = (_ends[:, 0] >= 0) & (_ends[:, 1] >= 0) & (numpy.abs(_ends[:, 0] - _ends[:, 1]) == 1)",
                      "    _off = numpy.zeros(n - 1)",
                      "    _off[numpy.minimum(_ends[_inner, 0], _ends[_inner, 1])] = -_kk[_inner]",
                      "    return _diag, _off"])
            + function(f"stiffness_matrix({c.sig_and('n=N')})", "Dense K, shape (n, n); only for n <= MAX_DENSE.",
                       [*_dense_limit("stiffness_matrix", "; use stiffness_bands()"),
                        f"    _diag, _off = stiffness_bands({c.kw_and('n=n')})",
                        "    _K = numpy.diag(_diag) + numpy.diag(_off, 1) + numpy.diag(_off, -1)",
                        *ring, "    return _K"])
            + function(f"mass_matrix({c.sig_and('n=N')})", "Dense M, shape (n, n); only for n <= MAX_DENSE.",
                       [*_dense_limit("mass_matrix", ""), f"    return numpy.diag(masses({c.kw_and('n=n')}))"]))


def _dense_limit(name: str, hint: str) -> list[str]:
    """The refusal of a dense (n, n) function past MAX_DENSE."""
    return ["    if n > _MAX_DENSE:",
            f"        raise ValueError(f'{name}: n = {{n}} > MAX_DENSE = {{_MAX_DENSE}}{hint}')"]


def _spectrum(c: _Context) -> list[str]:
    """omega2(n) (and mode_omega(n) for closed forms): closed form, ring helper or bidiagonal SVD."""
    if c.modes.omega2 is not None:
        return _closed_form_spectrum(c)
    if c.chain.left is End.RING:
        return _ring_spectrum(c)
    rigid = "(tuple(range(n)),)" if c.chain.left is End.FREE and c.chain.right is End.FREE else "()"
    return (function(f"omega2({c.sig_and('n=N')})",
                     "Squared angular frequencies (no closed form), ascending, shape (n,).\n\n"
                     "Singular values of the bidiagonal spring factor G (GᵀG = M^-1/2 K M^-1/2) by bisection on its\n"
                     "Golub–Kahan form: accurate to float64 in the relative sense at any positive masses and springs\n"
                     "whose sqrt(k/m) lie within 1e140 of each other (beyond, up to MAX_DENSE masses, the dense\n"
                     "spring-factor SVD); rigid modes exactly 0. Cost O(n²).", _bidiagonal_omega2(c))
            + function("_dense_omega2(_m, _k, _ends, n)",
                       "ω² of an open chain of n masses by the spring-factor helper below (its globals bound here).",
                       [f"    N, SPRING_ENDS, RIGID_PIECES = n, _ends, {rigid}",
                        textwrap.indent(helper_source().rstrip("\n"), "    "),
                        "",
                        "    return _accurate_modes(_m, _k)[0]"]))


def _closed_form_spectrum(c: _Context) -> list[str]:
    """omega2(n) sorted and mode_omega(n) in index order, from the uniform chain's closed form."""
    lo, _ = c.modes.j_range
    expr = p(c.modes.omega2.subs({c.model.j: sp.Symbol("_j"), c.model.n: sp.Symbol("n")}))
    js = f"    _j = numpy.arange({lo}, n + {lo}, dtype=float)"
    return (function(f"omega2({c.sig_and('n=N')})", "Closed-form squared angular frequencies, ascending, shape (n,).",
                     [js, f"    return numpy.sort(numpy.broadcast_to({expr}, (n,)))"])
            + function(f"mode_omega({c.sig_and('n=N')})",
                       f"Closed-form angular frequencies of modes j = {lo} … n{lo - 1:+d} in index order (not sorted), "
                       "shape (n,).\n\n"
                       "The order of the chain's sine/cosine/Fourier transform: the numeric exact solution of long\n"
                       "uniform chains takes its frequencies from here.",
                       [js, f"    return numpy.sqrt(numpy.broadcast_to({expr}, (n,)))"]))


def _ring_spectrum(c: _Context) -> list[str]:
    """omega2(n) of an index-dependent ring: the spring-factor helper, its globals bound per call."""
    kw = c.kw
    return (function(f"omega2({c.sig_and('n=N')})",
                     "Squared angular frequencies (index-dependent ring), ascending, shape (n,).\n\n"
                     "The spring-factor route (subtraction-free LDLᵀ of K, one-sided Jacobi SVD of its factor), as\n"
                     "the dense modules run it: accurate to float64 in the relative sense at any positive masses\n"
                     "and springs; the rigid mode exactly 0. Cost O(n³).",
                     [f"    return _ring_omega2(masses({c.kw_and('n=n')}), spring_constants({c.kw_and('n=n')}), spring_ends(n=n), n)"])
            + function("_ring_omega2(_m, _k, _ends, n)",
                       "ω² of a ring of n masses by the spring-factor helper below (its globals bound here).",
                       ["    N, SPRING_ENDS, RIGID_PIECES = n, _ends, (tuple(range(n)),)",
                        textwrap.indent(helper_source().rstrip("\n"), "    "),
                        "",
                        "    return _accurate_modes(_m, _k)[0]"]))


def _bidiagonal_omega2(c: _Context) -> list[str]:
    """The body of omega2() for an index-dependent open chain (no closed form).

    D = M^-1/2 K M^-1/2 = GᵀG with G = diag(√k) B M^-1/2 (B the spring incidence), and G of an
    open chain is bidiagonal (square after appending a zero row, whose zero singular value is
    dropped, or is the rigid mode). ω are G's singular values, found by bisection on the
    Golub–Kahan form (zero diagonal, off-diagonals interleaving G's entries; LAPACK stebz with
    a tolerance below the underflow threshold), which is accurate in the relative sense for any
    positive masses and springs (Demmel & Kahan 1990; LAPACK's dbdsvdx does the same). Forming
    D and calling eigh_tridiagonal is not: its small ω² lose ~κ(D)·ε.
    """
    ch = c.chain
    out = [f"    _rm = 1.0 / numpy.sqrt(masses({c.kw_and('n=n')}))", f"    _rk = numpy.sqrt(spring_constants({c.kw_and('n=n')}))"]
    if ch.left is End.WALL:  # rows: the wall spring (mass 0), then spring r between r-1 and r
        out += ["    _a = _rk[:n] * _rm", "    _b = _rk[1:n] * _rm[:n - 1]"]
        if ch.right is End.WALL:
            out.append("    _a, _b = numpy.append(_a, 0.0), numpy.append(_b, _rk[n] * _rm[n - 1])")
    else:  # rows: spring r between r and r+1, then the right wall's spring or a zero row
        out += ["    _a = _rk[:n - 1] * _rm[:n - 1]", "    _b = _rk[:n - 1] * _rm[1:]",
                "    _a = numpy.append(_a, " + ("_rk[n - 1] * _rm[n - 1]" if ch.right is End.WALL else "0.0") + ")"]
    return out + ["    _s = _a.shape[0]",
                  "    _t = numpy.empty(2 * _s - 1)",
                  "    _t[0::2], _t[1::2] = _a, _b",
                  "    # scaled by a power of 2 to a largest entry in [1/2, 1): stebz's pivot floor and stopping",
                  "    # tolerance are tiny * max(1, max entry²) absolute, 2e-10 at entries of 1e149",
                  "    _sc = numpy.ldexp(1.0, -numpy.frexp(numpy.max(_t))[1])",
                  "    _nz = _t[_t > 0]",
                  "    if _nz.size < 2 or numpy.max(_nz) <= 1e140 * numpy.min(_nz):",
                  "        _sv = scipy.linalg.eigh_tridiagonal(numpy.zeros(2 * _s), _t * _sc, eigvals_only=True, select='i',",
                  "                                            select_range=(_s, 2 * _s - 1), lapack_driver='stebz',",
                  "                                            tol=numpy.finfo(numpy.float64).tiny)",
                  "    elif n <= _MAX_DENSE:",
                  "        # entries more than 1e140 apart: stebz squares them (the small ones underflow), so the",
                  "        # spring-factor SVD of the dense modules (relatively accurate at any positive values; O(n³))",
                  f"        return _dense_omega2(masses({c.kw_and('n=n')}), spring_constants({c.kw_and('n=n')}), spring_ends(n=n), n)",
                  "    else:",
                  "        raise ValueError(f'omega2(): the spring factor\\'s entries sqrt(k/m) span more than 1e140 in a chain '",
                  "                         f'of {n} masses: float64 bisection cannot give its ω relative accuracy, and the '",
                  "                         f'dense spring-factor route takes at most MAX_DENSE = {_MAX_DENSE} masses')",
                  "    _w = (numpy.sort(numpy.abs(_sv))[_s - n:] / _sc) ** 2",
                  "    _w[:_RIGID_MODES] = 0.0",
                  "    return _w"]


#: The section writers of a chain module, in the order they appear in it.
SECTIONS = (_constants, _masses, _spring_coefficients, _spring_lists, _stencil, _acceleration, _energy,
            _spring_law, _loads, _damping, _matrices, _spectrum, band_section)


def render_chain_module(model: ChainModel, *, bundled: bool = True) -> str:
    """Stencil module for a chain (``model``: its template derivation); its size does not depend on n.

    Like :func:`derive.codegen.render_module`: ``bundled`` changes only the regenerate line, and
    the source is byte-identical for the same scene.
    """
    c = _Context(model, chain_modes(model))
    head = module_head(model.scene, c.params, _doc(c), scipy=True, bundled=bundled)
    return render(head, SECTIONS, c)


__all__ = ["SECTIONS", "render_chain_module"]
